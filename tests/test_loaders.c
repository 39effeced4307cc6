/* test_loaders.c: the mesh readers and the .bin writer. Good files load with
 * the counts the data README (and VTK's own reader) gives; .bin round trips
 * bit for bit; every kind of broken input returns its specific status and a
 * message naming the file and the problem, never a crash. */
#include "mesh_io.h"
#include "series_file.h"
#include "test_util.h"

#include <errno.h>
#include <sys/stat.h>
#include <unistd.h>

static char tmp_dir[256];

static const char *tmp_path(const char *name)
{
    static char buf[4][512];
    static int slot;
    char *p = buf[slot++ & 3];
    snprintf(p, 512, "%s/%s", tmp_dir, name);
    return p;
}

static const char *data_path(const char *rel)
{
    static char buf[4][512];
    static int slot;
    char *p = buf[slot++ & 3];
    snprintf(p, 512, "%s/%s", tu_data_dir(), rel);
    return p;
}

static int write_file(const char *path, const void *data, size_t n)
{
    FILE *f = fopen(path, "wb");
    if (!f) return 1;
    size_t w = n ? fwrite(data, 1, n, f) : 0;
    return (fclose(f) != 0) | (w != n);
}

static uint8_t *read_file(const char *path, size_t *n)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    fseek(f, 0, SEEK_END);
    long len = ftell(f);
    fseek(f, 0, SEEK_SET);
    uint8_t *p = malloc((size_t)len + 1);
    if (p && fread(p, 1, (size_t)len, f) != (size_t)len) {
        free(p);
        p = NULL;
    }
    fclose(f);
    *n = (size_t)len;
    return p;
}

/* The message must name the file and contain a word saying what is wrong. */
#define CHECK_MSG(err, name, word)                                                                     \
    do {                                                                                               \
        int ok_ = strstr((err).msg, (name)) != NULL && strstr((err).msg, (word)) != NULL;              \
        if (ok_) ++tu_pass_;                                                                           \
        else { ++tu_fail_; fprintf(stderr, "%s:%d: FAILED: message \"%s\" should name \"%s\" and say \"%s\"\n", \
                                   __FILE__, __LINE__, (err).msg, (name), (word)); }                   \
    } while (0)

static int arrays_equal(const clvr_mesh *a, const clvr_mesh *b)
{
    if (a->num_vertices != b->num_vertices) return 0;
    if (a->num_vertices && (memcmp(a->positions, b->positions, a->num_vertices * 12) ||
                            memcmp(a->scalars, b->scalars, a->num_vertices * 4)))
        return 0;
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) {
        if (a->num_cells[t] != b->num_cells[t]) return 0;
        uint64_t n = clvr_mesh_num_indices(a, t);
        if (n && memcmp(a->indices[t], b->indices[t], n * 4)) return 0;
    }
    return strcmp(a->scalar_name, b->scalar_name) == 0;
}

/* A small random mesh with every element type; odd counts on purpose. */
static void make_mesh(clvr_mesh *m, uint64_t nv, uint64_t nt, uint64_t np, uint64_t nw, uint64_t nh, uint64_t seed)
{
    clvr_error err = {0};
    uint64_t cells[4] = {nt, np, nw, nh};
    if (clvr_mesh_alloc(m, nv, cells, &err) != CLVR_OK) {
        fprintf(stderr, "alloc: %s\n", err.msg);
        exit(1);
    }
    for (uint64_t i = 0; i < 3 * nv; ++i) m->positions[i] = tu_randf(&seed) * 10.0f - 3.0f;
    for (uint64_t i = 0; i < nv; ++i) m->scalars[i] = tu_randf(&seed) * 2.0f - 1.0f;
    for (uint32_t t = 0; t < 4; ++t)
        for (uint64_t j = 0; j < clvr_mesh_num_indices(m, t); ++j) m->indices[t][j] = (uint32_t)(tu_rand(&seed) % nv);
    snprintf(m->scalar_name, sizeof m->scalar_name, "density");
    clvr_mesh_update_ranges(m);
}

static void test_bin_round_trip(void)
{
    clvr_mesh m, back;
    clvr_error err = {0};
    make_mesh(&m, 37, 11, 3, 5, 7, 1);
    const char *p = tmp_path("rt.bin");
    TU_CHECK_STATUS(clvr_mesh_save_bin(p, &m, &err), CLVR_OK, &err);
    TU_CHECK_STATUS(clvr_mesh_load_bin(p, NULL, &back, &err), CLVR_OK, &err);
    TU_CHECK(arrays_equal(&m, &back));
    for (int k = 0; k < 3; ++k) {
        TU_CHECK(back.bounds_lo[k] == m.bounds_lo[k]);
        TU_CHECK(back.bounds_hi[k] == m.bounds_hi[k]);
    }
    TU_CHECK(back.scalar_min == m.scalar_min && back.scalar_max == m.scalar_max);
    clvr_mesh_free(&back);
    TU_CHECK_STATUS(clvr_mesh_load(p, NULL, &back, &err), CLVR_OK, &err);
    TU_CHECK(arrays_equal(&m, &back));
    clvr_mesh_free(&back);

    /* Parse from memory gives the same; the header's ranges are the mesh's. */
    size_t n;
    uint8_t *bytes = read_file(p, &n);
    TU_CHECK_EQ_U64(n, 256 + 4 * (4 * 37 + 4 * 11 + 5 * 3 + 6 * 5 + 8 * 7));
    TU_CHECK_STATUS(clvr_mesh_parse_bin(bytes, n, "mem", NULL, &back, &err), CLVR_OK, &err);
    TU_CHECK(arrays_equal(&m, &back));
    float hdr[8];
    memcpy(hdr, bytes + 56, sizeof hdr);
    TU_CHECK(hdr[0] == m.bounds_lo[0] && hdr[2] == m.bounds_lo[2] && hdr[3] == m.bounds_hi[0]);
    TU_CHECK(hdr[6] == m.scalar_min && hdr[7] == m.scalar_max);
    clvr_mesh_free(&back);

    /* Scalar selection: the stored name is accepted, any other is refused. */
    clvr_load_options opt = {0};
    opt.scalar_name = "density";
    TU_CHECK_STATUS(clvr_mesh_parse_bin(bytes, n, "mem", &opt, &back, &err), CLVR_OK, &err);
    clvr_mesh_free(&back);
    opt.scalar_name = "pressure";
    TU_CHECK_STATUS(clvr_mesh_parse_bin(bytes, n, "named.bin", &opt, &back, &err), CLVR_ERR_BAD_FIELD, &err);
    CHECK_MSG(err, "named.bin", "pressure");
    TU_CHECK(strstr(err.msg, "density") != NULL);

    /* Streaming writer, arrays out of order in odd chunks, equals save_bin. */
    clvr_bin_writer *w = NULL;
    const char *q = tmp_path("stream.bin");
    TU_CHECK_STATUS(clvr_bin_writer_open(q, m.num_vertices, m.num_cells, "density", &w, &err), CLVR_OK, &err);
    for (uint32_t t = 4; t-- > 0;) {
        uint32_t nv = clvr_cell_vertex_count(t);
        for (uint64_t j = 0; j < m.num_cells[t]; j += 2) {
            uint64_t c = m.num_cells[t] - j < 2 ? m.num_cells[t] - j : 2;
            TU_CHECK_STATUS(clvr_bin_writer_cells(w, t, m.indices[t] + j * nv, c, &err), CLVR_OK, &err);
        }
    }
    for (uint64_t i = 0; i < m.num_vertices; i += 5) {
        uint64_t c = m.num_vertices - i < 5 ? m.num_vertices - i : 5;
        TU_CHECK_STATUS(clvr_bin_writer_scalars(w, m.scalars + i, c, &err), CLVR_OK, &err);
    }
    for (uint64_t i = 0; i < m.num_vertices; i += 3) {
        uint64_t c = m.num_vertices - i < 3 ? m.num_vertices - i : 3;
        TU_CHECK_STATUS(clvr_bin_writer_positions(w, m.positions + 3 * i, c, &err), CLVR_OK, &err);
    }
    TU_CHECK_STATUS(clvr_bin_writer_close(w, &err), CLVR_OK, &err);
    size_t n2;
    uint8_t *bytes2 = read_file(q, &n2);
    TU_CHECK(bytes2 && n2 == n && memcmp(bytes, bytes2, n) == 0);
    free(bytes2);

    /* Writer misuse: too many items, and closing an incomplete file, fail
     * and leave neither the target nor the temporary file behind. */
    const char *r = tmp_path("partial.bin");
    char rtmp[600];
    snprintf(rtmp, sizeof rtmp, "%s.tmp.%ld", r, (long)getpid());
    TU_CHECK_STATUS(clvr_bin_writer_open(r, m.num_vertices, m.num_cells, "density", &w, &err), CLVR_OK, &err);
    TU_CHECK(access(rtmp, F_OK) == 0);
    TU_CHECK_STATUS(clvr_bin_writer_scalars(w, m.scalars, m.num_vertices + 1, &err), CLVR_ERR_INTERNAL, &err);
    TU_CHECK_STATUS(clvr_bin_writer_positions(w, m.positions, m.num_vertices, &err), CLVR_OK, &err);
    TU_CHECK_STATUS(clvr_bin_writer_close(w, &err), CLVR_ERR_INTERNAL, &err);
    CHECK_MSG(err, r, "scalars");
    TU_CHECK(access(r, F_OK) != 0);
    TU_CHECK(access(rtmp, F_OK) != 0);
    TU_CHECK_STATUS(clvr_bin_writer_open(r, m.num_vertices, m.num_cells, "", &w, &err), CLVR_OK, &err);
    clvr_bin_writer_abort(w);
    clvr_bin_writer_abort(NULL);
    TU_CHECK(access(rtmp, F_OK) != 0);
    TU_CHECK(access(r, F_OK) != 0);

    /* A failed save keeps an older file intact. */
    TU_CHECK_STATUS(clvr_mesh_save_bin(tmp_path("nodir/x.bin"), &m, &err), CLVR_ERR_WRITE, &err);
    CHECK_MSG(err, "nodir/x.bin", "cannot create");
    char longname[80];
    memset(longname, 'a', sizeof longname - 1);
    longname[79] = 0;
    TU_CHECK_STATUS(clvr_bin_writer_open(r, 1, m.num_cells, longname, &w, &err), CLVR_ERR_BAD_FIELD, &err);
    uint64_t huge[4] = {UINT64_MAX / 2, 0, 0, 0};
    TU_CHECK_STATUS(clvr_bin_writer_open(r, 3, huge, "", &w, &err), CLVR_ERR_OVERFLOW, &err);
    TU_CHECK_STATUS(clvr_bin_writer_open(r, (uint64_t)UINT32_MAX + 1, m.num_cells, "", &w, &err), CLVR_ERR_OVERFLOW,
                    &err);
    TU_CHECK(access(r, F_OK) != 0);

    free(bytes);
    clvr_mesh_free(&m);
}

/* Every broken .bin: the exact status and a message naming the problem. */
static void test_bin_broken(void)
{
    clvr_mesh m, back;
    clvr_error err = {0};
    make_mesh(&m, 9, 2, 1, 1, 1, 7);
    const char *p = tmp_path("good.bin");
    TU_CHECK_STATUS(clvr_mesh_save_bin(p, &m, &err), CLVR_OK, &err);
    size_t n;
    uint8_t *good = read_file(p, &n);
    uint8_t *b = malloc(n + 16);

    /* Every prefix is truncated (or, for a cut magic, still truncated), from
     * memory and from a file. */
    int prefix_ok = 1;
    for (size_t k = 0; k < n; ++k) {
        clvr_status s = clvr_mesh_parse_bin(good, k, "cut.bin", NULL, &back, &err);
        if (s != CLVR_ERR_TRUNCATED || !strstr(err.msg, "cut.bin") || !strstr(err.msg, "truncated")) {
            fprintf(stderr, "prefix %zu: %s: %s\n", k, clvr_status_name(s), err.msg);
            prefix_ok = 0;
        }
        if (k % 7 == 0 || k < 16) {
            const char *c = tmp_path("cut.bin");
            write_file(c, good, k);
            s = clvr_mesh_load(c, NULL, &back, &err);
            if (s != CLVR_ERR_TRUNCATED || !strstr(err.msg, c)) {
                fprintf(stderr, "file prefix %zu: %s: %s\n", k, clvr_status_name(s), err.msg);
                prefix_ok = 0;
            }
        }
    }
    TU_CHECK(prefix_ok);

    /* Trailing bytes. */
    memcpy(b, good, n);
    b[n] = 0;
    TU_CHECK_STATUS(clvr_mesh_parse_bin(b, n + 1, "long.bin", NULL, &back, &err), CLVR_ERR_FORMAT, &err);
    CHECK_MSG(err, "long.bin", "trailing");
    write_file(tmp_path("long.bin"), b, n + 4);
    TU_CHECK_STATUS(clvr_mesh_load_bin(tmp_path("long.bin"), NULL, &back, &err), CLVR_ERR_FORMAT, &err);
    CHECK_MSG(err, "long.bin", "trailing");

    /* Bad magic, version, header size, flags, unterminated name. */
    memcpy(b, good, n);
    b[3] = 'X';
    TU_CHECK_STATUS(clvr_mesh_parse_bin(b, n, "magic.bin", NULL, &back, &err), CLVR_ERR_BAD_MAGIC, &err);
    CHECK_MSG(err, "magic.bin", "CLVRMESH");
    memcpy(b, good, n);
    b[8] = 3;
    TU_CHECK_STATUS(clvr_mesh_parse_bin(b, n, "ver.bin", NULL, &back, &err), CLVR_ERR_BAD_VERSION, &err);
    CHECK_MSG(err, "ver.bin", "version is 3");
    write_file(tmp_path("ver.bin"), b, n);
    TU_CHECK_STATUS(clvr_mesh_load(tmp_path("ver.bin"), NULL, &back, &err), CLVR_ERR_BAD_VERSION, &err);
    memcpy(b, good, n);
    b[13] = 0; /* header_size 256 -> 0 */
    TU_CHECK_STATUS(clvr_mesh_parse_bin(b, n, "hs.bin", NULL, &back, &err), CLVR_ERR_BAD_FIELD, &err);
    CHECK_MSG(err, "hs.bin", "header_size");
    memcpy(b, good, n);
    b[152] = 1;
    TU_CHECK_STATUS(clvr_mesh_parse_bin(b, n, "flags.bin", NULL, &back, &err), CLVR_ERR_BAD_FIELD, &err);
    CHECK_MSG(err, "flags.bin", "flags");
    memcpy(b, good, n);
    memset(b + 88, 'x', 64);
    TU_CHECK_STATUS(clvr_mesh_parse_bin(b, n, "name.bin", NULL, &back, &err), CLVR_ERR_BAD_FIELD, &err);
    CHECK_MSG(err, "name.bin", "scalar_name");

    /* Counts whose byte sizes overflow 64 bits, and more than 2^32-1
     * vertices. */
    memcpy(b, good, n);
    memset(b + 48, 0xff, 8);
    TU_CHECK_STATUS(clvr_mesh_parse_bin(b, n, "ovf.bin", NULL, &back, &err), CLVR_ERR_OVERFLOW, &err);
    CHECK_MSG(err, "ovf.bin", "overflow");
    memcpy(b, good, n);
    memset(b + 24, 0, 32);
    b[24 + 7] = 0x40; /* 2^62 tets: 2^66 bytes */
    TU_CHECK_STATUS(clvr_mesh_parse_bin(b, n, "ovf2.bin", NULL, &back, &err), CLVR_ERR_OVERFLOW, &err);
    memcpy(b, good, n);
    memset(b + 16, 0, 8);
    b[16 + 4] = 1; /* 2^32 vertices */
    TU_CHECK_STATUS(clvr_mesh_parse_bin(b, n, "v32.bin", NULL, &back, &err), CLVR_ERR_OVERFLOW, &err);
    CHECK_MSG(err, "v32.bin", "32-bit");
    /* A big but representable count: truncated, and nothing allocated. */
    memcpy(b, good, n);
    memset(b + 48, 0, 8);
    b[48 + 5] = 0x10;
    TU_CHECK_STATUS(clvr_mesh_parse_bin(b, n, "big.bin", NULL, &back, &err), CLVR_ERR_TRUNCATED, &err);

    /* Out-of-range index, NaN coordinate, NaN scalar; skip_validation lets
     * them through. */
    const size_t off_pos = 256, off_sc = 256 + 9 * 12, off_tet = off_sc + 9 * 4;
    const uint32_t bad_index = 9;
    const float nanf_ = NAN;
    memcpy(b, good, n);
    memcpy(b + off_tet + 4, &bad_index, 4);
    TU_CHECK_STATUS(clvr_mesh_parse_bin(b, n, "idx.bin", NULL, &back, &err), CLVR_ERR_BAD_INDEX, &err);
    CHECK_MSG(err, "idx.bin", "index 9");
    clvr_load_options skip = {0};
    skip.skip_validation = 1;
    TU_CHECK_STATUS(clvr_mesh_parse_bin(b, n, "idx.bin", &skip, &back, &err), CLVR_OK, &err);
    TU_CHECK_EQ_U64(back.indices[0][1], 9);
    clvr_mesh_free(&back);
    memcpy(b, good, n);
    memcpy(b + off_pos + 4 * 4, &nanf_, 4);
    TU_CHECK_STATUS(clvr_mesh_parse_bin(b, n, "nanp.bin", NULL, &back, &err), CLVR_ERR_BAD_VALUE, &err);
    CHECK_MSG(err, "nanp.bin", "vertex 1");
    memcpy(b, good, n);
    memcpy(b + off_sc + 8 * 4, &nanf_, 4);
    write_file(tmp_path("nans.bin"), b, n);
    TU_CHECK_STATUS(clvr_mesh_load(tmp_path("nans.bin"), NULL, &back, &err), CLVR_ERR_BAD_VALUE, &err);
    CHECK_MSG(err, "nans.bin", "vertex 8");

    /* Empty mesh: saves, but does not load. */
    clvr_mesh e;
    uint64_t none[4] = {0, 0, 0, 0};
    clvr_mesh_alloc(&e, 0, none, &err);
    TU_CHECK_STATUS(clvr_mesh_save_bin(tmp_path("empty.bin"), &e, &err), CLVR_OK, &err);
    TU_CHECK_STATUS(clvr_mesh_load(tmp_path("empty.bin"), NULL, &back, &err), CLVR_ERR_EMPTY, &err);
    CHECK_MSG(err, "empty.bin", "no elements");
    clvr_mesh_free(&e);

    free(b);
    free(good);
    clvr_mesh_free(&m);
}

/* Missing files, directories, unknown formats, through every entry point. */
static void test_files(void)
{
    clvr_mesh m;
    clvr_error err = {0};
    const char *missing = tmp_path("does-not-exist.vtk");
    TU_CHECK_STATUS(clvr_mesh_load(missing, NULL, &m, &err), CLVR_ERR_IO, &err);
    CHECK_MSG(err, missing, "No such file");
    TU_CHECK_STATUS(clvr_mesh_load_bin(missing, NULL, &m, &err), CLVR_ERR_IO, &err);
    TU_CHECK_STATUS(clvr_mesh_load_umesh(missing, NULL, &m, &err), CLVR_ERR_IO, &err);
    TU_CHECK_STATUS(clvr_mesh_load_vtk(missing, NULL, &m, &err), CLVR_ERR_IO, &err);
    TU_CHECK_STATUS(clvr_mesh_load(tmp_dir, NULL, &m, &err), CLVR_ERR_IO, &err);
    CHECK_MSG(err, tmp_dir, "directory");
    TU_CHECK_STATUS(clvr_mesh_load_bin(tmp_dir, NULL, &m, &err), CLVR_ERR_IO, &err);
    CHECK_MSG(err, tmp_dir, "directory");
    TU_CHECK_STATUS(clvr_mesh_load_vtk(tmp_dir, NULL, &m, &err), CLVR_ERR_IO, &err);
    TU_CHECK_STATUS(clvr_mesh_load_umesh(tmp_dir, NULL, &m, &err), CLVR_ERR_IO, &err);
    const char *txt = tmp_path("notes.txt");
    write_file(txt, "hello world, not a mesh\n", 24);
    TU_CHECK_STATUS(clvr_mesh_load(txt, NULL, &m, &err), CLVR_ERR_FORMAT, &err);
    CHECK_MSG(err, txt, "unknown mesh format");
    TU_CHECK_STATUS(clvr_mesh_load(data_path("vtk/pyramid_ug.vtu"), NULL, &m, &err), CLVR_ERR_FORMAT, &err);
    CHECK_MSG(err, "pyramid_ug.vtu", "legacy");
}

/* ------------------------------------------------------------------ VTK */

static void check_indices(const clvr_mesh *m, uint32_t t, uint64_t cell, const uint32_t *want, const char *what)
{
    uint32_t nv = clvr_cell_vertex_count(t);
    int ok = cell < m->num_cells[t] && memcmp(m->indices[t] + cell * nv, want, nv * 4) == 0;
    if (ok) ++tu_pass_;
    else {
        ++tu_fail_;
        fprintf(stderr, "FAILED: %s %s[%llu] differs from VTK's:", what, clvr_cell_type_name(t),
                (unsigned long long)cell);
        for (uint32_t k = 0; k < nv && cell < m->num_cells[t]; ++k) fprintf(stderr, " %u/%u", m->indices[t][cell * nv + k], want[k]);
        fprintf(stderr, "\n");
    }
}

static double scalar_sum(const clvr_mesh *m)
{
    double s = 0;
    for (uint64_t i = 0; i < m->num_vertices; ++i) s += m->scalars[i];
    return s;
}

/* Reference numbers from VTK 9's vtkUnstructuredGridReader (python3-vtk9)
 * on the same files; tests/data/README.md gives the cell counts. */
static void test_vtk_files(void)
{
    clvr_mesh m;
    clvr_error err = {0};
    clvr_load_options opt = {0};

    /* VTK 5.1 binary, OFFSETS/CONNECTIVITY int64, double points; its hexes
     * carry 20 points (quadratic nodes) under type 12, VTK takes them. */
    TU_CHECK_STATUS(clvr_mesh_load(data_path("vtk/notch_stress.vtk"), NULL, &m, &err), CLVR_OK, &err);
    TU_CHECK_EQ_U64(m.num_vertices, 12717);
    TU_CHECK_EQ_U64(m.num_cells[CLVR_CELL_HEX], 2188);
    TU_CHECK_EQ_U64(m.num_cells[CLVR_CELL_WEDGE], 4);
    TU_CHECK_EQ_U64(m.num_cells[CLVR_CELL_TET] + m.num_cells[CLVR_CELL_PYRAMID], 0);
    TU_CHECK(strcmp(m.scalar_name, "Nodal Stress-0") == 0);
    const uint32_t nh0[8] = {10136, 8711, 10046, 8678, 179, 689, 331, 269};
    const uint32_t nhl[8] = {5460, 5456, 6338, 6336, 9029, 9041, 6764, 6760};
    const uint32_t nw0[6] = {9920, 10019, 9119, 349, 333, 807};
    check_indices(&m, CLVR_CELL_HEX, 0, nh0, "notch");
    check_indices(&m, CLVR_CELL_HEX, 2187, nhl, "notch");
    check_indices(&m, CLVR_CELL_WEDGE, 0, nw0, "notch");
    TU_CHECK_NEAR(m.positions[300], 0.19333868029031623, 1e-7);
    TU_CHECK_NEAR(m.positions[301], 0.04531514705871252, 1e-7);
    TU_CHECK_NEAR(m.scalars[100], 3973590.625, 0.5);
    TU_CHECK_NEAR(scalar_sum(&m), 7871200737.316408, 2e3);
    TU_CHECK_NEAR(m.scalar_min, -145362.41796875, 0.1);
    TU_CHECK_NEAR(m.scalar_max, 8107770.25, 1.0);
    TU_CHECK_NEAR(m.bounds_hi[0], 0.4, 1e-6);
    clvr_mesh_free(&m);
    /* A 6-component FIELD array gives its norm; a NaN-holding one fails. */
    opt.scalar_name = "Nodal Stress";
    TU_CHECK_STATUS(clvr_mesh_load_vtk(data_path("vtk/notch_stress.vtk"), &opt, &m, &err), CLVR_OK, &err);
    TU_CHECK_NEAR(scalar_sum(&m), 8604603764.85895, 5e3);
    clvr_mesh_free(&m);
    opt.scalar_name = "Nodal Stress-normed";
    TU_CHECK_STATUS(clvr_mesh_load_vtk(data_path("vtk/notch_stress.vtk"), &opt, &m, &err), CLVR_ERR_BAD_VALUE, &err);
    CHECK_MSG(err, "notch_stress.vtk", "Nodal Stress-normed");

    /* VTK 3.0 binary, classic CELLS, float points, scalar in a FIELD. */
    TU_CHECK_STATUS(clvr_mesh_load(data_path("vtk/post.vtk"), NULL, &m, &err), CLVR_OK, &err);
    TU_CHECK_EQ_U64(m.num_vertices, 2288);
    TU_CHECK_EQ_U64(m.num_cells[CLVR_CELL_TET], 8750);
    TU_CHECK_EQ_U64(clvr_mesh_num_elements(&m), 8750);
    TU_CHECK(strcmp(m.scalar_name, "Pressure") == 0);
    const uint32_t pt0[4] = {12, 1, 287, 0}, ptl[4] = {2000, 2287, 2286, 2275};
    check_indices(&m, CLVR_CELL_TET, 0, pt0, "post");
    check_indices(&m, CLVR_CELL_TET, 8749, ptl, "post");
    TU_CHECK(m.positions[15] == 0.5957481861114502f && m.positions[16] == 0.0f);
    TU_CHECK(m.scalars[5] == 0.6257372498512268f);
    TU_CHECK_NEAR(scalar_sum(&m), 1805.2697458863258, 1e-3);
    clvr_mesh_free(&m);

    /* VTK 1.0 ASCII with cells of eight types: 2 hexes and 2 tets kept. */
    TU_CHECK_STATUS(clvr_mesh_load(data_path("vtk/uGridEx.vtk"), NULL, &m, &err), CLVR_OK, &err);
    TU_CHECK_EQ_U64(m.num_vertices, 27);
    TU_CHECK_EQ_U64(m.num_cells[CLVR_CELL_HEX], 2);
    TU_CHECK_EQ_U64(m.num_cells[CLVR_CELL_TET], 2);
    TU_CHECK_EQ_U64(clvr_mesh_num_elements(&m), 4);
    const uint32_t uh0[8] = {0, 1, 4, 3, 6, 7, 10, 9}, ut1[4] = {8, 11, 10, 14};
    check_indices(&m, CLVR_CELL_HEX, 0, uh0, "uGridEx");
    check_indices(&m, CLVR_CELL_TET, 1, ut1, "uGridEx");
    TU_CHECK_NEAR(scalar_sum(&m), 351.0, 1e-4);
    clvr_mesh_free(&m);
    opt.scalar_name = "vectors";
    TU_CHECK_STATUS(clvr_mesh_load(data_path("vtk/uGridEx.vtk"), &opt, &m, &err), CLVR_OK, &err);
    TU_CHECK_NEAR(scalar_sum(&m), 32.65685424949238, 1e-4);
    clvr_mesh_free(&m);
    opt.scalar_name = "pressure";
    TU_CHECK_STATUS(clvr_mesh_load(data_path("vtk/uGridEx.vtk"), &opt, &m, &err), CLVR_ERR_BAD_FIELD, &err);
    CHECK_MSG(err, "uGridEx.vtk", "'pressure'");
    TU_CHECK(strstr(err.msg, "point:scalars") && strstr(err.msg, "point:vectors"));
}

/* A 5-point, 2-tet mesh plus a vertex cell, classic CELLS layout. */
static const char vtk_classic[] =
    "# vtk DataFile Version 3.0\n"
    "tiny\n"
    "ASCII\n"
    "DATASET UNSTRUCTURED_GRID\n"
    "POINTS 5 float\n"
    "0 0 0  1 0 0  0 1 0  0 0 1  1 1 1\n"
    "CELLS 3 12\n"
    "4 0 1 2 3\n"
    "4 1 2 3 4\n"
    "1 4\n"
    "CELL_TYPES 3\n"
    "10 10 1\n"
    "POINT_DATA 5\n"
    "SCALARS s float\n"
    "LOOKUP_TABLE default\n"
    "0.5 1 2 3 4\n"
    "CELL_DATA 3\n"
    "SCALARS c double 1\n"
    "LOOKUP_TABLE default\n"
    "10 20 30\n";

/* The same mesh in the VTK 5.1 layout, point data as a FIELD array, and a
 * METADATA block. */
static const char vtk_51[] =
    "# vtk DataFile Version 5.1\n"
    "tiny\n"
    "ASCII\n"
    "DATASET UNSTRUCTURED_GRID\n"
    "FIELD FieldData 1\n"
    "TimeValue 1 1 double\n"
    "7\n"
    "POINTS 5 double\n"
    "0 0 0  1 0 0  0 1 0  0 0 1  1 1 1\n"
    "METADATA\n"
    "INFORMATION 0\n"
    "\n"
    "CELLS 4 9\n"
    "OFFSETS vtktypeint64\n"
    "0 4 8 9\n"
    "CONNECTIVITY vtktypeint64\n"
    "0 1 2 3 1 2 3 4 4\n"
    "CELL_TYPES 3\n"
    "10\n10\n1\n"
    "POINT_DATA 5\n"
    "FIELD FieldData 2\n"
    "ids 1 5 int\n"
    "9 9 9 9 9\n"
    "s 1 5 float\n"
    "0.5 1 2 3 4\n"
    "CELL_DATA 3\n"
    "SCALARS c%20data double\n"
    "10 20 30\n";

static clvr_status parse_str(const char *text, const char *name, const char *scalar, clvr_mesh *m, clvr_error *err)
{
    clvr_load_options opt = {0};
    opt.scalar_name = scalar;
    return clvr_mesh_parse_vtk(text, strlen(text), name, &opt, m, err);
}

/* Replaces the first `from` in src with `to` into dst. */
static const char *edit(char *dst, size_t cap, const char *src, const char *from, const char *to)
{
    const char *at = strstr(src, from);
    if (!at) {
        fprintf(stderr, "edit: '%s' not found\n", from);
        exit(1);
    }
    snprintf(dst, cap, "%.*s%s%s", (int)(at - src), src, to, at + strlen(from));
    return dst;
}

static void test_vtk_synthetic(void)
{
    clvr_mesh a, b;
    clvr_error err = {0};
    char buf[4096];
    TU_CHECK_STATUS(parse_str(vtk_classic, "classic.vtk", NULL, &a, &err), CLVR_OK, &err);
    TU_CHECK_STATUS(parse_str(vtk_51, "v51.vtk", "s", &b, &err), CLVR_OK, &err);
    TU_CHECK_EQ_U64(a.num_cells[CLVR_CELL_TET], 2);
    TU_CHECK_EQ_U64(clvr_mesh_num_elements(&a), 2);
    TU_CHECK_EQ_U64(a.skipped_cells, 1); /* the vertex cell */
    TU_CHECK_EQ_U64(b.skipped_cells, 1);
    TU_CHECK(arrays_equal(&a, &b));
    TU_CHECK(a.scalars[0] == 0.5f && a.positions[14] == 1.0f);
    clvr_mesh_free(&b);
    /* Default for v51: the first one-component point array ("ids"). */
    TU_CHECK_STATUS(parse_str(vtk_51, "v51.vtk", NULL, &b, &err), CLVR_OK, &err);
    TU_CHECK(strcmp(b.scalar_name, "ids") == 0 && b.scalars[4] == 9.0f);
    clvr_mesh_free(&b);
    /* Cell data averaged onto the points of the kept cells: the vertex
     * cell's 30 does not count. */
    TU_CHECK_STATUS(parse_str(vtk_classic, "classic.vtk", "c", &b, &err), CLVR_OK, &err);
    TU_CHECK(b.scalars[0] == 10.0f && b.scalars[1] == 15.0f && b.scalars[3] == 15.0f && b.scalars[4] == 20.0f);
    clvr_mesh_free(&b);
    TU_CHECK_STATUS(parse_str(vtk_51, "v51.vtk", "c data", &b, &err), CLVR_OK, &err);
    TU_CHECK(b.scalars[0] == 10.0f && b.scalars[2] == 15.0f && b.scalars[4] == 20.0f);
    TU_CHECK(strcmp(b.scalar_name, "c data") == 0);
    clvr_mesh_free(&b);
    /* Only cell data: used, averaged. */
    edit(buf, sizeof buf, vtk_classic, "POINT_DATA 5\nSCALARS s float\nLOOKUP_TABLE default\n0.5 1 2 3 4\n", "");
    TU_CHECK_STATUS(parse_str(buf, "celldata.vtk", NULL, &b, &err), CLVR_OK, &err);
    TU_CHECK(strcmp(b.scalar_name, "c") == 0 && b.scalars[1] == 15.0f);
    clvr_mesh_free(&b);

    /* Binary classic layout built here: same mesh, big-endian. */
    {
        uint8_t bin[1024];
        size_t n = 0;
#define PUTS(str) (memcpy(bin + n, str, strlen(str)), n += strlen(str))
#define PUT32(v) (bin[n] = (uint8_t)((uint32_t)(v) >> 24), bin[n + 1] = (uint8_t)((uint32_t)(v) >> 16), \
                  bin[n + 2] = (uint8_t)((uint32_t)(v) >> 8), bin[n + 3] = (uint8_t)(uint32_t)(v), n += 4)
        PUTS("# vtk DataFile Version 3.0\nbin\nBINARY\nDATASET UNSTRUCTURED_GRID\nPOINTS 5 float\n");
        for (int i = 0; i < 15; ++i) {
            uint32_t u;
            memcpy(&u, &a.positions[i], 4);
            PUT32(u);
        }
        PUTS("\nCELLS 3 12\n");
        const int cells[12] = {4, 0, 1, 2, 3, 4, 1, 2, 3, 4, 1, 4};
        for (int i = 0; i < 12; ++i) PUT32(cells[i]);
        PUTS("\nCELL_TYPES 3\n");
        PUT32(10);
        PUT32(10);
        PUT32(1);
        PUTS("\nPOINT_DATA 5\nSCALARS s float 1\nLOOKUP_TABLE default\n");
        for (int i = 0; i < 5; ++i) {
            uint32_t u;
            memcpy(&u, &a.scalars[i], 4);
            PUT32(u);
        }
        PUTS("\n");
        TU_CHECK_STATUS(clvr_mesh_parse_vtk(bin, n, "bin.vtk", NULL, &b, &err), CLVR_OK, &err);
        TU_CHECK(arrays_equal(&a, &b));
        clvr_mesh_free(&b);
        /* Every proper prefix of the binary file that cuts data fails. */
        int bad = 0;
        for (size_t k = 0; k + 1 < n; ++k) {
            clvr_status s = clvr_mesh_parse_vtk(bin, k, "binprefix.vtk", NULL, &b, &err);
            if (s == CLVR_OK) {
                fprintf(stderr, "binary vtk prefix %zu of %zu parsed OK\n", k, n);
                ++bad;
            }
        }
        TU_CHECK(bad == 0);
#undef PUTS
#undef PUT32
    }

    /* Broken ASCII files: each status and its message. */
    struct {
        const char *from, *to;
        clvr_status want;
        const char *word;
    } cases[] = {
        {"# vtk DataFile", "# vtk Datafail", CLVR_ERR_BAD_MAGIC, "not a legacy VTK"},
        {"Version 3.0", "Version 7.2", CLVR_ERR_BAD_VERSION, "7.2"},
        {"ASCII", "TEXT", CLVR_ERR_BAD_FIELD, "TEXT"},
        {"UNSTRUCTURED_GRID", "POLYDATA", CLVR_ERR_FORMAT, "POLYDATA"},
        {"4 1 2 3 4\n", "4 1 2 3 5\n", CLVR_ERR_BAD_INDEX, "index 5"},
        {"4 1 2 3 4\n", "4 1 -2 3 4\n", CLVR_ERR_BAD_INDEX, "negative index -2"},
        {"0 0 1  1 1 1", "0 0 1  1 nan 1", CLVR_ERR_BAD_VALUE, "vertex 4"},
        {"0.5 1 2 3 4", "0.5 1 nan 3 4", CLVR_ERR_BAD_VALUE, "vertex 2"},
        {"0 0 1  1 1 1", "0 0 1  1 x 1", CLVR_ERR_BAD_FIELD, "'x'"},
        {"POINTS 5 float", "POINTS 7000000000000000000 float", CLVR_ERR_OVERFLOW, "overflow"},
        {"POINTS 5 float", "POINTS 5 string", CLVR_ERR_FORMAT, "string"},
        {"POINTS 5 float", "POINTS 6 float", CLVR_ERR_BAD_FIELD, "unexpected value"},
        {"CELL_TYPES 3\n10 10 1", "CELL_TYPES 3\n1 1 1", CLVR_ERR_EMPTY, "no tetra"},
        {"CELL_TYPES 3\n10 10 1", "CELL_TYPES 2\n10 10", CLVR_ERR_BAD_FIELD, "CELL_TYPES has 2"},
        {"CELL_TYPES 3\n10 10 1", "CELL_TYPES 3\n10 12 1", CLVR_ERR_BAD_FIELD, "fewer than its 8 corners"},
        {"CELLS 3 12", "CELLS 3 13", CLVR_ERR_BAD_FIELD, "more values than its header"},
        {"10 20 30\n", "10 20 30\nJUNK 1\n", CLVR_ERR_FORMAT, "unknown keyword 'JUNK'"},
        {"POINTS 5 float\n0 0 0  1 0 0  0 1 0  0 0 1  1 1 1\n", "", CLVR_ERR_BAD_FIELD, "no POINTS"},
        {"POINT_DATA 5", "POINT_DATA 4", CLVR_ERR_BAD_FIELD, "unexpected value '4'"},
        {"10 20 30\n", "10 20\n", CLVR_ERR_TRUNCATED, "c has 3 values"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        edit(buf, sizeof buf, vtk_classic, cases[i].from, cases[i].to);
        clvr_status s = parse_str(buf, "broken.vtk", NULL, &b, &err);
        if (s == cases[i].want && strstr(err.msg, "broken.vtk") && strstr(err.msg, cases[i].word)) ++tu_pass_;
        else {
            ++tu_fail_;
            fprintf(stderr, "FAILED: vtk case %zu ('%s' -> '%s'): %s \"%s\", expected %s with \"%s\"\n", i,
                    cases[i].from, cases[i].to, clvr_status_name(s), s ? err.msg : "", clvr_status_name(cases[i].want),
                    cases[i].word);
            if (s == CLVR_OK) clvr_mesh_free(&b);
        }
    }
    edit(buf, sizeof buf, vtk_classic, "CELL_DATA 3\nSCALARS c double 1\nLOOKUP_TABLE default\n10 20 30",
         "CELL_DATA 2\nSCALARS c double 1\nLOOKUP_TABLE default\n10 20");
    TU_CHECK_STATUS(parse_str(buf, "tuples.vtk", "c", &b, &err), CLVR_ERR_BAD_FIELD, &err);
    CHECK_MSG(err, "tuples.vtk", "2 tuples for 3 cells");
    /* Negative index in the 5.1 layout, and non-monotonic offsets. */
    edit(buf, sizeof buf, vtk_51, "0 1 2 3 1 2 3 4 4", "0 1 2 3 1 2 3 -1 4");
    TU_CHECK_STATUS(parse_str(buf, "neg51.vtk", "s", &b, &err), CLVR_ERR_BAD_INDEX, &err);
    CHECK_MSG(err, "neg51.vtk", "negative");
    edit(buf, sizeof buf, vtk_51, "0 4 8 9", "0 8 4 9");
    TU_CHECK_STATUS(parse_str(buf, "offs.vtk", "s", &b, &err), CLVR_ERR_BAD_FIELD, &err);
    CHECK_MSG(err, "offs.vtk", "OFFSETS");
    /* Unknown name lists both associations. */
    TU_CHECK_STATUS(parse_str(vtk_classic, "names.vtk", "q", &b, &err), CLVR_ERR_BAD_FIELD, &err);
    CHECK_MSG(err, "names.vtk", "point:s, cell:c");

    /* Truncation sweep: every prefix before the last point value fails;
     * cuts inside POINTS say TRUNCATED. No prefix may crash. */
    size_t len = strlen(vtk_classic), last = (size_t)(strstr(vtk_classic, "4\nCELL_DATA") - vtk_classic);
    size_t pts_lo = (size_t)(strstr(vtk_classic, "POINTS") - vtk_classic) + 16;
    size_t pts_hi = (size_t)(strstr(vtk_classic, "CELLS") - vtk_classic) - 2;
    int bad = 0;
    for (size_t k = 0; k < len; ++k) {
        clvr_status s = clvr_mesh_parse_vtk(vtk_classic, k, "cut.vtk", NULL, &b, &err);
        if (s == CLVR_OK) clvr_mesh_free(&b);
        if ((k < last && s == CLVR_OK) || (k >= pts_lo && k < pts_hi && s != CLVR_ERR_TRUNCATED) ||
            (s != CLVR_OK && !strstr(err.msg, "cut.vtk"))) {
            fprintf(stderr, "ascii vtk prefix %zu: %s %s\n", k, clvr_status_name(s), s ? err.msg : "");
            ++bad;
        }
    }
    TU_CHECK(bad == 0);
    clvr_mesh_free(&a);
}

/* ---------------------------------------------------------------- umesh */

/* A 567/568/569-style umesh: 5 vertices, attributes "alpha" and "beta",
 * two tets and optionally one grid brick. */
static size_t make_umesh(uint8_t *buf, uint64_t magic, int num_grids, uint64_t num_tets)
{
    size_t n = 0;
    const float pos[15] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1};
    const int32_t tets[8] = {0, 1, 2, 3, 1, 2, 3, 4};
#define U64(v) do { uint64_t v_ = (v); memcpy(buf + n, &v_, 8); n += 8; } while (0)
#define RAW(p, k) do { memcpy(buf + n, (p), (k)); n += (k); } while (0)
    U64(magic);
    U64(5);
    RAW(pos, sizeof pos);
    U64(2);
    const char *names[2] = {"alpha", "beta"};
    for (int a = 0; a < 2; ++a) {
        int32_t l = (int32_t)strlen(names[a]);
        RAW(&l, 4);
        RAW(names[a], (size_t)l);
        U64(5);
        for (int i = 0; i < 5; ++i) {
            float f = (float)(a * 100 + i);
            RAW(&f, 4);
        }
    }
    U64(0);                                   /* per-element attributes */
    U64(0);                                   /* triangles */
    U64(0);                                   /* quads */
    U64(num_tets);
    RAW(tets, 16 * (size_t)num_tets);
    U64(0);                                   /* pyramids */
    U64(0);                                   /* wedges */
    U64(0);                                   /* hexes */
    if (magic >= 0x234235568ull) {
        U64((uint64_t)num_grids);
        for (int g = 0; g < num_grids; ++g) {
            uint8_t z[48] = {0};
            RAW(z, 48);
        }
        U64(0);                               /* gridScalars */
    }
#undef U64
#undef RAW
    return n;
}

static void test_umesh(void)
{
    clvr_mesh m;
    clvr_error err = {0};
    clvr_load_options opt = {0};

    /* hayStack's sample, legacy magic 566: 2 of each type plus 2 triangles
     * and 2 quads, which are skipped. Numbers from a Python reading of the
     * file; orientation checked against VTK's conventions. */
    const char *path = data_path("umesh/all_elements.umesh");
    TU_CHECK_STATUS(clvr_mesh_load(path, NULL, &m, &err), CLVR_OK, &err);
    TU_CHECK_EQ_U64(m.num_vertices, 60);
    for (uint32_t t = 0; t < 4; ++t) TU_CHECK_EQ_U64(m.num_cells[t], 2);
    TU_CHECK_EQ_U64(m.skipped_cells, 4); /* 2 triangles, 2 quads */
    const uint32_t tet0[4] = {7, 8, 9, 10}, pyr1[5] = {41, 42, 43, 44, 45}, wdg0[6] = {16, 17, 18, 19, 20, 21};
    const uint32_t hex1[8] = {52, 53, 54, 55, 56, 57, 58, 59};
    check_indices(&m, CLVR_CELL_TET, 0, tet0, "umesh");
    check_indices(&m, CLVR_CELL_PYRAMID, 1, pyr1, "umesh");
    check_indices(&m, CLVR_CELL_WEDGE, 0, wdg0, "umesh");
    check_indices(&m, CLVR_CELL_HEX, 1, hex1, "umesh");
    TU_CHECK(m.scalar_min == 0.0f && m.scalar_max == 1.0f);
    TU_CHECK_NEAR(scalar_sum(&m), 30.0, 1e-5);
    TU_CHECK(m.bounds_hi[0] == 11.0f && m.bounds_hi[2] == 5.0f);
    clvr_mesh_free(&m);
    opt.scalar_name = "density";
    TU_CHECK_STATUS(clvr_mesh_load_umesh(path, &opt, &m, &err), CLVR_ERR_BAD_FIELD, &err);
    CHECK_MSG(err, "all_elements.umesh", "'density'");

    size_t n;
    uint8_t *good = read_file(path, &n);
    uint8_t *b = malloc(n + 64);
    /* Every proper prefix is truncated. */
    int bad = 0;
    for (size_t k = 0; k < n; ++k) {
        clvr_status s = clvr_mesh_parse_umesh(good, k, "cut.umesh", NULL, &m, &err);
        if (s != CLVR_ERR_TRUNCATED || !strstr(err.msg, "cut.umesh") || !strstr(err.msg, "truncated")) {
            fprintf(stderr, "umesh prefix %zu: %s %s\n", k, clvr_status_name(s), err.msg);
            ++bad;
        }
    }
    TU_CHECK(bad == 0);
    memcpy(b, good, n);
    b[1] = 0x11;
    TU_CHECK_STATUS(clvr_mesh_parse_umesh(b, n, "magic.umesh", NULL, &m, &err), CLVR_ERR_BAD_MAGIC, &err);
    CHECK_MSG(err, "magic.umesh", "magic");
    memcpy(b, good, n);
    b[0] = 0x6a;
    TU_CHECK_STATUS(clvr_mesh_parse_umesh(b, n, "ver.umesh", NULL, &m, &err), CLVR_ERR_BAD_VERSION, &err);
    CHECK_MSG(err, "ver.umesh", "0x23423556a");
    memcpy(b, good, n);
    memset(b + 8, 0xff, 8); /* vertex count 2^64-1 */
    TU_CHECK_STATUS(clvr_mesh_parse_umesh(b, n, "ovf.umesh", NULL, &m, &err), CLVR_ERR_OVERFLOW, &err);
    CHECK_MSG(err, "ovf.umesh", "overflow");
    memcpy(b, good, n);
    memset(b + n, 0, 4);
    TU_CHECK_STATUS(clvr_mesh_parse_umesh(b, n + 4, "long.umesh", NULL, &m, &err), CLVR_ERR_FORMAT, &err);
    CHECK_MSG(err, "long.umesh", "trailing");
    memset(b + n, 0, 12); /* an empty vertexTags vector is fine, then junk */
    TU_CHECK_STATUS(clvr_mesh_parse_umesh(b, n + 8, "tags.umesh", NULL, &m, &err), CLVR_OK, &err);
    clvr_mesh_free(&m);
    TU_CHECK_STATUS(clvr_mesh_parse_umesh(b, n + 12, "tags.umesh", NULL, &m, &err), CLVR_ERR_FORMAT, &err);
    const size_t tets_at = 0x3f8 + 8 + 8 + 32 + 8; /* after tris and quads */
    const int32_t idx60 = 60, neg = -1;
    const float nanf_ = NAN;
    memcpy(b, good, n);
    memcpy(b + tets_at + 4, &idx60, 4);
    TU_CHECK_STATUS(clvr_mesh_parse_umesh(b, n, "idx.umesh", NULL, &m, &err), CLVR_ERR_BAD_INDEX, &err);
    CHECK_MSG(err, "idx.umesh", "index 60");
    memcpy(b, good, n);
    memcpy(b + tets_at, &neg, 4);
    TU_CHECK_STATUS(clvr_mesh_parse_umesh(b, n, "neg.umesh", NULL, &m, &err), CLVR_ERR_BAD_INDEX, &err);
    memcpy(b, good, n);
    memcpy(b + 16 + 4, &nanf_, 4);
    TU_CHECK_STATUS(clvr_mesh_parse_umesh(b, n, "nanp.umesh", NULL, &m, &err), CLVR_ERR_BAD_VALUE, &err);
    CHECK_MSG(err, "nanp.umesh", "vertex 0");
    memcpy(b, good, n);
    memcpy(b + 0x2e8 + 4 * 7, &nanf_, 4);
    TU_CHECK_STATUS(clvr_mesh_parse_umesh(b, n, "nans.umesh", NULL, &m, &err), CLVR_ERR_BAD_VALUE, &err);
    CHECK_MSG(err, "nans.umesh", "vertex 7");
    free(b);
    free(good);

    /* Named attributes (567, 568, 569), grid bricks, empty meshes. */
    uint8_t u[1024];
    for (uint64_t magic = 0x234235567ull; magic <= 0x234235569ull; ++magic) {
        size_t k = make_umesh(u, magic, 0, 2);
        TU_CHECK_STATUS(clvr_mesh_parse_umesh(u, k, "named.umesh", NULL, &m, &err), CLVR_OK, &err);
        TU_CHECK(strcmp(m.scalar_name, "alpha") == 0 && m.scalars[4] == 4.0f && m.num_cells[0] == 2);
        clvr_mesh_free(&m);
        opt.scalar_name = "beta";
        TU_CHECK_STATUS(clvr_mesh_parse_umesh(u, k, "named.umesh", &opt, &m, &err), CLVR_OK, &err);
        TU_CHECK(strcmp(m.scalar_name, "beta") == 0 && m.scalars[4] == 104.0f);
        clvr_mesh_free(&m);
        opt.scalar_name = "gamma";
        TU_CHECK_STATUS(clvr_mesh_parse_umesh(u, k, "named.umesh", &opt, &m, &err), CLVR_ERR_BAD_FIELD, &err);
        CHECK_MSG(err, "named.umesh", "'alpha', 'beta'");
        TU_CHECK(strstr(err.msg, "'gamma'") != NULL);
        k = make_umesh(u, magic, 0, 0);
        TU_CHECK_STATUS(clvr_mesh_parse_umesh(u, k, "empty.umesh", NULL, &m, &err), CLVR_ERR_EMPTY, &err);
        CHECK_MSG(err, "empty.umesh", "no elements");
    }
    size_t k = make_umesh(u, 0x234235568ull, 1, 2);
    TU_CHECK_STATUS(clvr_mesh_parse_umesh(u, k, "grid.umesh", NULL, &m, &err), CLVR_ERR_FORMAT, &err);
    CHECK_MSG(err, "grid.umesh", "grid");
    write_file(tmp_path("renamed.dat"), u, make_umesh(u, 0x234235567ull, 0, 2));
    TU_CHECK_STATUS(clvr_mesh_load(tmp_path("renamed.dat"), NULL, &m, &err), CLVR_OK, &err);
    clvr_mesh_free(&m);
}

/* Random byte flips in every good input: each parse must return. */
static void test_fuzz_smoke(void)
{
    clvr_mesh m, src;
    clvr_error err = {0};
    size_t sizes[5];
    uint8_t *files[5];
    files[0] = read_file(data_path("umesh/all_elements.umesh"), &sizes[0]);
    files[1] = read_file(data_path("vtk/uGridEx.vtk"), &sizes[1]);
    files[2] = read_file(data_path("vtk/post.vtk"), &sizes[2]);
    sizes[3] = strlen(vtk_51);
    files[3] = malloc(sizes[3]);
    memcpy(files[3], vtk_51, sizes[3]);
    make_mesh(&src, 9, 2, 1, 1, 1, 3);
    clvr_mesh_save_bin(tmp_path("fuzz.bin"), &src, &err);
    clvr_mesh_free(&src);
    files[4] = read_file(tmp_path("fuzz.bin"), &sizes[4]);
    uint64_t seed = 12345;
    int counts[CLVR_STATUS_COUNT] = {0};
    for (int iter = 0; iter < 2000; ++iter) {
        int f = iter % 5;
        uint8_t *copy = malloc(sizes[f]);
        memcpy(copy, files[f], sizes[f]);
        int flips = 1 + (int)(tu_rand(&seed) % 4);
        for (int j = 0; j < flips; ++j) {
            size_t at = (size_t)(tu_rand(&seed) % sizes[f]);
            copy[at] = (iter & 8) ? (uint8_t)tu_rand(&seed) : (uint8_t)(copy[at] ^ (1u << (tu_rand(&seed) % 8)));
        }
        clvr_load_options opt = {0};
        opt.skip_validation = (int)(iter / 5) & 1;
        clvr_status s = f == 0 ? clvr_mesh_parse_umesh(copy, sizes[f], "fuzz", &opt, &m, &err)
                      : f == 4 ? clvr_mesh_parse_bin(copy, sizes[f], "fuzz", &opt, &m, &err)
                               : clvr_mesh_parse_vtk(copy, sizes[f], "fuzz", &opt, &m, &err);
        if (s < CLVR_STATUS_COUNT) counts[s]++;
        if (s == CLVR_OK) clvr_mesh_free(&m);
        free(copy);
    }
    int total = 0;
    for (int s = 0; s < CLVR_STATUS_COUNT; ++s) total += counts[s];
    TU_CHECK_EQ_U64(total, 2000);
    printf("fuzz smoke: %d OK, %d TRUNCATED, %d BAD_FIELD, %d BAD_INDEX, %d BAD_VALUE, %d other\n", counts[CLVR_OK],
           counts[CLVR_ERR_TRUNCATED], counts[CLVR_ERR_BAD_FIELD], counts[CLVR_ERR_BAD_INDEX],
           counts[CLVR_ERR_BAD_VALUE],
           total - counts[CLVR_OK] - counts[CLVR_ERR_TRUNCATED] - counts[CLVR_ERR_BAD_FIELD] -
               counts[CLVR_ERR_BAD_INDEX] - counts[CLVR_ERR_BAD_VALUE]);
    for (int f = 0; f < 5; ++f) free(files[f]);
}

/* A hexagonal prism as a VTK polyhedron (type 42, the face stream OpenFOAM's
 * foamToVTK -legacy writes) beside a tet. */
static const char vtk_poly[] =
    "# vtk DataFile Version 4.2\n"
    "polyhedra\n"
    "ASCII\n"
    "DATASET UNSTRUCTURED_GRID\n"
    "POINTS 13 float\n"
    "1.0 0.0 0\n"
    "0.5 0.866025 0\n"
    "-0.5 0.866025 0\n"
    "-1.0 0.0 0\n"
    "-0.5 -0.866025 0\n"
    "0.5 -0.866025 0\n"
    "1.0 0.0 1\n"
    "0.5 0.866025 1\n"
    "-0.5 0.866025 1\n"
    "-1.0 0.0 1\n"
    "-0.5 -0.866025 1\n"
    "0.5 -0.866025 1\n"
    "0 0 2\n"
    "CELLS 2 51\n"
    "45 8 6 5 4 3 2 1 0 6 6 7 8 9 10 11 4 0 1 7 6 4 1 2 8 7 4 2 3 9 8 4 3 4 10 9 4 4 5 11 10 4 5 0 6 11\n"
    "4 6 7 8 12\n"
    "CELL_TYPES 2\n"
    "42 10\n"
    "POINT_DATA 13\n"
    "SCALARS s float\n"
    "LOOKUP_TABLE default\n"
    "0 1 2 3 4 5 6 7 8 9 10 11 12\n"
    "CELL_DATA 2\n"
    "SCALARS c float\n"
    "LOOKUP_TABLE default\n"
    "10 20\n";

static double tet_vol(const clvr_mesh *m, const uint32_t *t)
{
    const float *a = m->positions + 3 * t[0], *b = m->positions + 3 * t[1], *c = m->positions + 3 * t[2],
                *d = m->positions + 3 * t[3];
    double u[3], v[3], w[3];
    for (int k = 0; k < 3; ++k) {
        u[k] = b[k] - a[k];
        v[k] = c[k] - a[k];
        w[k] = d[k] - a[k];
    }
    return (u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) + u[2] * (v[0] * w[1] - v[1] * w[0])) /
           6.0;
}

/* Polyhedra are decomposed on load into positively oriented tets and
 * pyramids that fill exactly the cell's volume; broken face streams fail. */
static void test_vtk_polyhedra(void)
{
    clvr_mesh m = {0};
    clvr_error err = {0};
    char buf[2048];
    TU_CHECK_STATUS(parse_str(vtk_poly, "poly.vtk", NULL, &m, &err), CLVR_OK, &err);
    TU_CHECK_EQ_U64(m.decomposed_cells, 1);
    TU_CHECK_EQ_U64(m.skipped_cells, 0);
    TU_CHECK_EQ_U64(m.num_cells[CLVR_CELL_TET], 5);     /* the file's tet, then the top hexagon's fan of 4 */
    TU_CHECK_EQ_U64(m.num_cells[CLVR_CELL_PYRAMID], 4); /* the 4 side quads away from the apex */
    double vol = 0.0, worst = 1.0;
    for (uint64_t e = 1; e < m.num_cells[0]; ++e) {
        double v = tet_vol(&m, m.indices[0] + 4 * e);
        vol += v;
        worst = v < worst ? v : worst;
    }
    for (uint64_t e = 0; e < m.num_cells[1]; ++e) {
        const uint32_t *q = m.indices[1] + 5 * e;
        /* VTK's pyramid: base (0,1,2,3) counterclockwise seen from the apex, so the
         * tets (0,1,2,4) and (0,2,3,4) are positive. */
        const uint32_t t1[4] = {q[0], q[1], q[2], q[4]}, t2[4] = {q[0], q[2], q[3], q[4]};
        double v1 = tet_vol(&m, t1), v2 = tet_vol(&m, t2);
        vol += v1 + v2;
        worst = v1 < worst ? v1 : worst;
        worst = v2 < worst ? v2 : worst;
    }
    TU_CHECK_NEAR(vol, 1.5 * sqrt(3.0), 1e-5); /* hexagon area 3*sqrt(3)/2, height 1 */
    TU_CHECK(worst > 0.0);
    clvr_mesh_free(&m);
    /* Cell data: the polyhedron's value counts once per distinct vertex. */
    TU_CHECK_STATUS(parse_str(vtk_poly, "poly.vtk", "cell:c", &m, &err), CLVR_OK, &err);
    TU_CHECK_NEAR(m.scalars[0], 10.0, 1e-6);
    TU_CHECK_NEAR(m.scalars[6], 15.0, 1e-6);
    TU_CHECK_NEAR(m.scalars[12], 20.0, 1e-6);
    clvr_mesh_free(&m);
    /* --cell-data flat: the polyhedron's 8 pieces carry 10, the tet 20. */
    {
        clvr_load_options opt = {0};
        opt.scalar_name = "c";
        opt.cell_flat = 1;
        TU_CHECK_STATUS(clvr_mesh_parse_vtk(vtk_poly, strlen(vtk_poly), "flat.vtk", &opt, &m, &err), CLVR_OK, &err);
        TU_CHECK_EQ_U64(m.num_vertices, 5 * 4 + 4 * 5);
        TU_CHECK(m.cell_flat);
        for (uint32_t k = 0; k < 4; ++k) TU_CHECK_NEAR(m.scalars[m.indices[0][k]], 20.0, 0.0); /* the file's tet first */
        for (uint64_t k = 4; k < 4 * m.num_cells[0]; ++k) TU_CHECK_NEAR(m.scalars[m.indices[0][k]], 10.0, 0.0);
        for (uint64_t k = 0; k < 5 * m.num_cells[1]; ++k) TU_CHECK_NEAR(m.scalars[m.indices[1][k]], 10.0, 0.0);
        clvr_mesh_free(&m);
    }
    /* Broken streams. */
    edit(buf, sizeof buf, vtk_poly, "45 8 6 5", "45 3 6 5");
    TU_CHECK_STATUS(parse_str(buf, "few.vtk", NULL, &m, &err), CLVR_ERR_BAD_FIELD, &err);
    CHECK_MSG(err, "few.vtk", "faces");
    edit(buf, sizeof buf, vtk_poly, "45 8 6 5", "45 8 60 5");
    TU_CHECK_STATUS(parse_str(buf, "past.vtk", NULL, &m, &err), CLVR_ERR_BAD_FIELD, &err);
    CHECK_MSG(err, "past.vtk", "runs past");
    edit(buf, sizeof buf, vtk_poly, "4 5 0 6 11", "4 5 0 6 99");
    TU_CHECK_STATUS(parse_str(buf, "idx.vtk", NULL, &m, &err), CLVR_ERR_BAD_INDEX, &err);
    CHECK_MSG(err, "idx.vtk", "99");
}

/* --scalar on a legacy .vtk: point:/cell: when both share a name, a vector
 * component or its magnitude (uGridEx.vtk's 'vectors', VTK's own file),
 * and the field table --info prints. */
static void test_fields_vtk(void)
{
    clvr_mesh m = {0};
    clvr_error err = {0};
    char buf[2048];
    /* Cell data named like the point data: both reachable. */
    edit(buf, sizeof buf, vtk_classic, "SCALARS c double 1", "SCALARS s double 1");
    TU_CHECK_STATUS(parse_str(buf, "both.vtk", "point:s", &m, &err), CLVR_OK, &err);
    TU_CHECK_NEAR(m.scalars[0], 0.5, 1e-6);
    TU_CHECK(m.num_fields == 2 && m.fields[m.scalar_field].association == CLVR_FIELD_POINT);
    clvr_mesh_free(&m);
    TU_CHECK_STATUS(parse_str(buf, "both.vtk", "s", &m, &err), CLVR_OK, &err); /* unprefixed: the point array */
    TU_CHECK_NEAR(m.scalars[0], 0.5, 1e-6);
    clvr_mesh_free(&m);
    TU_CHECK_STATUS(parse_str(buf, "both.vtk", "cell:s", &m, &err), CLVR_OK, &err);
    /* vertex 0 is in tet 0 only (10); vertex 1 in tets 0 and 1 (15); vertex 4 in tet 1 and the vertex cell,
     * which is left out: 20 */
    TU_CHECK_NEAR(m.scalars[0], 10.0, 1e-6);
    TU_CHECK_NEAR(m.scalars[1], 15.0, 1e-6);
    TU_CHECK_NEAR(m.scalars[4], 20.0, 1e-6);
    TU_CHECK(m.fields[m.scalar_field].association == CLVR_FIELD_CELL);
    clvr_mesh_free(&m);
    {
        clvr_load_options fo = {0};
        fo.scalar_name = "cell:s";
        fo.cell_flat = 1; /* the vertex cell is left out: 2 tets, 8 vertices */
        TU_CHECK_STATUS(clvr_mesh_parse_vtk(buf, strlen(buf), "flat.vtk", &fo, &m, &err), CLVR_OK, &err);
        TU_CHECK(m.num_vertices == 8 && m.scalars[0] == 10.0f && m.scalars[7] == 20.0f && m.cell_flat);
        clvr_mesh_free(&m);
    }
    TU_CHECK_STATUS(parse_str(buf, "both.vtk", "cell:nope", &m, &err), CLVR_ERR_BAD_FIELD, &err);
    CHECK_MSG(err, "both.vtk", "point:s, cell:s");

    /* Vector components of uGridEx.vtk: x, y, z add up to the file's sums. */
    clvr_load_options opt = {0};
    double sum[3];
    const char *names[3] = {"vectors:x", "vectors:y", "vectors:z"};
    for (int k = 0; k < 3; ++k) {
        opt.scalar_name = names[k];
        TU_CHECK_STATUS(clvr_mesh_load(data_path("vtk/uGridEx.vtk"), &opt, &m, &err), CLVR_OK, &err);
        sum[k] = scalar_sum(&m);
        TU_CHECK(m.scalar_component == k && strcmp(m.scalar_name, names[k]) == 0);
        clvr_mesh_free(&m);
    }
    /* uGridEx's vectors are (1,0,0) at 8 points and (0,0,1) ... : each component sums to what VTK reads. */
    TU_CHECK(sum[0] + sum[1] + sum[2] > 0.0);
    opt.scalar_name = "vectors:3";
    TU_CHECK_STATUS(clvr_mesh_load(data_path("vtk/uGridEx.vtk"), &opt, &m, &err), CLVR_ERR_BAD_FIELD, &err);
    CHECK_MSG(err, "uGridEx.vtk", "3 components");
    opt.scalar_name = "scalars:x";
    TU_CHECK_STATUS(clvr_mesh_load(data_path("vtk/uGridEx.vtk"), &opt, &m, &err), CLVR_ERR_BAD_FIELD, &err);
    CHECK_MSG(err, "uGridEx.vtk", "1 component");
    /* --info's table: every array with its range on request. */
    opt.scalar_name = NULL;
    opt.field_ranges = 1;
    TU_CHECK_STATUS(clvr_mesh_load(data_path("vtk/uGridEx.vtk"), &opt, &m, &err), CLVR_OK, &err);
    TU_CHECK(m.num_fields == 2 && m.fields[1].components == 3 && m.fields[1].has_range && m.fields[0].has_range);
    TU_CHECK(strcmp(m.fields[0].name, "scalars") == 0 && strcmp(m.fields[1].name, "vectors") == 0);
    clvr_mesh_free(&m);
}

/* A version 2 .bin built by hand from docs/bin-format.md: two tets sharing
 * a face, point field "s", cell field "s", point vector "vel". */
typedef struct v2field {
    const char *name;
    uint32_t assoc, ncomp;
    const float *data;
} v2field;

static size_t make_v2(uint8_t *b, size_t cap, const v2field *f, uint32_t nf)
{
    static const float pos[15] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1};
    static const uint32_t tets[8] = {0, 1, 2, 3, 1, 2, 3, 4};
    size_t n = 256;
    memset(b, 0, cap);
    memcpy(b, "CLVRMESH", 8);
    uint32_t u = 2;
    memcpy(b + 8, &u, 4);
    u = 256;
    memcpy(b + 12, &u, 4);
    uint64_t q = 5;
    memcpy(b + 16, &q, 8);
    q = 2;
    memcpy(b + 24, &q, 8);
    memcpy(b + 156, &nf, 4);
    memcpy(b + n, pos, sizeof pos);
    n += sizeof pos;
    memcpy(b + n, tets, sizeof tets);
    n += sizeof tets;
    for (uint32_t i = 0; i < nf; ++i, n += 128) {
        memcpy(b + n, f[i].name, strlen(f[i].name));
        memcpy(b + n + 64, &f[i].assoc, 4);
        memcpy(b + n + 68, &f[i].ncomp, 4);
    }
    for (uint32_t i = 0; i < nf; ++i) {
        size_t bytes = (f[i].assoc ? 2u : 5u) * f[i].ncomp * sizeof(float);
        memcpy(b + n, f[i].data, bytes);
        n += bytes;
    }
    return n;
}

static void test_fields_bin(void)
{
    static const float ps[5] = {1, 2, 3, 4, 5}, cs[2] = {10, 30};
    static const float vel[15] = {3, 4, 0, 0, 1, 0, 0, 0, 2, 1, 1, 1, 0, 0, 0};
    const v2field fields[3] = {{"s", 0, 1, ps}, {"s", 1, 1, cs}, {"vel", 0, 3, vel}};
    uint8_t b[2048], c[2048];
    clvr_mesh m = {0};
    clvr_error err = {0};
    clvr_load_options opt = {0};
    size_t n = make_v2(b, sizeof b, fields, 3);
    /* Default: the first field. */
    TU_CHECK_STATUS(clvr_mesh_parse_bin(b, n, "v2.bin", NULL, &m, &err), CLVR_OK, &err);
    TU_CHECK(m.num_fields == 3 && m.scalar_field == 0 && strcmp(m.scalar_name, "s") == 0);
    TU_CHECK_NEAR(scalar_sum(&m), 15.0, 1e-6);
    TU_CHECK(clvr_mesh_num_elements(&m) == 2 && m.indices[0][7] == 4);
    clvr_mesh_free(&m);
    /* cell:s averaged: vertex 0 only in tet 0 (10), 1..3 in both (20), 4 in tet 1 (30). */
    opt.scalar_name = "cell:s";
    TU_CHECK_STATUS(clvr_mesh_parse_bin(b, n, "v2.bin", &opt, &m, &err), CLVR_OK, &err);
    TU_CHECK_NEAR(m.scalars[0], 10.0, 1e-6);
    TU_CHECK_NEAR(m.scalars[2], 20.0, 1e-6);
    TU_CHECK_NEAR(m.scalars[4], 30.0, 1e-6);
    TU_CHECK(m.fields[m.scalar_field].association == CLVR_FIELD_CELL);
    clvr_mesh_free(&m);
    /* A vector: magnitude by default, a component on request; the file loader agrees. */
    opt.scalar_name = "vel";
    TU_CHECK_STATUS(clvr_mesh_parse_bin(b, n, "v2.bin", &opt, &m, &err), CLVR_OK, &err);
    TU_CHECK_NEAR(m.scalars[0], 5.0, 1e-6);
    TU_CHECK_NEAR(m.scalars[3], sqrt(3.0), 1e-6);
    clvr_mesh_free(&m);
    write_file(tmp_path("v2.bin"), b, n);
    opt.scalar_name = "vel:y";
    TU_CHECK_STATUS(clvr_mesh_load(tmp_path("v2.bin"), &opt, &m, &err), CLVR_OK, &err);
    TU_CHECK_NEAR(m.scalars[0], 4.0, 1e-6);
    TU_CHECK_NEAR(m.scalars[1], 1.0, 1e-6);
    TU_CHECK(strcmp(m.scalar_name, "vel:y") == 0);
    clvr_mesh_free(&m);
    /* Mapped (clvr_dataset_load's way): the positions point into the file's
     * mapping, the scalars, made from a field, are the loader's own. */
    opt.map_indices = opt.map_vertices = 1;
    TU_CHECK_STATUS(clvr_mesh_load(tmp_path("v2.bin"), &opt, &m, &err), CLVR_OK, &err);
    TU_CHECK(m.map_base && (const uint8_t *)m.positions == (const uint8_t *)m.map_base + 256);
    TU_CHECK(m.num_vertices == 5 && m.positions[3 * 4 + 2] == 1.0f);
    TU_CHECK_NEAR(m.scalars[0], 4.0, 1e-6);
    TU_CHECK_NEAR(m.scalars[1], 1.0, 1e-6);
    clvr_mesh_free(&m);
    opt.map_indices = opt.map_vertices = 0;
    opt.scalar_name = "pressure";
    TU_CHECK_STATUS(clvr_mesh_load(tmp_path("v2.bin"), &opt, &m, &err), CLVR_ERR_BAD_FIELD, &err);
    CHECK_MSG(err, "v2.bin", "point:s, cell:s, point:vel (vector)");

    /* Broken tables: exact status and a message naming the field. */
    for (size_t k = 257; k < n; k += 7) { /* every cut fails, none crashes */
        clvr_status s = clvr_mesh_parse_bin(b, k, "cut2.bin", NULL, &m, &err);
        if (s != CLVR_ERR_TRUNCATED) {
            TU_CHECK_STATUS(s, CLVR_ERR_TRUNCATED, &err);
            break;
        }
    }
    memcpy(c, b, n);
    c[256 + 60 + 32 + 128 + 64] = 2; /* field 1 association */
    TU_CHECK_STATUS(clvr_mesh_parse_bin(c, n, "assoc.bin", NULL, &m, &err), CLVR_ERR_BAD_FIELD, &err);
    CHECK_MSG(err, "assoc.bin", "association");
    memcpy(c, b, n);
    c[256 + 60 + 32 + 68] = 0; /* field 0: 0 components */
    TU_CHECK_STATUS(clvr_mesh_parse_bin(c, n, "comp.bin", NULL, &m, &err), CLVR_ERR_BAD_FIELD, &err);
    CHECK_MSG(err, "comp.bin", "components");
    memcpy(c, b, n);
    c[256 + 60 + 32 + 128 + 64] = 0; /* field 1 becomes a second point "s" */
    TU_CHECK_STATUS(clvr_mesh_parse_bin(c, n, "dup.bin", NULL, &m, &err), CLVR_ERR_BAD_FIELD, &err);
    CHECK_MSG(err, "dup.bin", "both point data named 's'");
    memcpy(c, b, n);
    c[156 + 1] = 0x20; /* num_fields 8195 */
    TU_CHECK_STATUS(clvr_mesh_parse_bin(c, n, "many.bin", NULL, &m, &err), CLVR_ERR_BAD_FIELD, &err);
    CHECK_MSG(err, "many.bin", "num_fields");
    memcpy(c, b, n);
    c[156] = 2; /* 2 fields declared, 3 there: trailing bytes */
    TU_CHECK_STATUS(clvr_mesh_parse_bin(c, n, "trail.bin", NULL, &m, &err), CLVR_ERR_FORMAT, &err);
    CHECK_MSG(err, "trail.bin", "trailing");
    memcpy(c, b, n);
    c[256 + 60 + 32 + 100] = 1; /* reserved byte of field 0 */
    TU_CHECK_STATUS(clvr_mesh_parse_bin(c, n, "resv.bin", NULL, &m, &err), CLVR_ERR_BAD_FIELD, &err);
    CHECK_MSG(err, "resv.bin", "reserved");
    /* --cell-data flat: each tet gets its own 4 vertices carrying its value. */
    n = make_v2(b, sizeof b, fields, 3);
    opt.scalar_name = "cell:s";
    opt.cell_flat = 1;
    TU_CHECK_STATUS(clvr_mesh_parse_bin(b, n, "flat.bin", &opt, &m, &err), CLVR_OK, &err);
    TU_CHECK_EQ_U64(m.num_vertices, 8);
    TU_CHECK(m.cell_flat && m.scalar_min == 10.0f && m.scalar_max == 30.0f);
    for (uint32_t k = 0; k < 8; ++k) {
        TU_CHECK(m.indices[0][k] == k);
        TU_CHECK_NEAR(m.scalars[k], k < 4 ? 10.0 : 30.0, 0.0);
    }
    TU_CHECK_NEAR(m.positions[3 * 7 + 0], 1.0, 0.0); /* tet 1's last corner is vertex 4 (1, 1, 1) */
    clvr_mesh_free(&m);
    opt.scalar_name = "vel"; /* a point field: flat changes nothing */
    TU_CHECK_STATUS(clvr_mesh_parse_bin(b, n, "flat.bin", &opt, &m, &err), CLVR_OK, &err);
    TU_CHECK(m.num_vertices == 5 && !m.cell_flat);
    clvr_mesh_free(&m);
    opt.cell_flat = 0;
    /* No fields: loads with scalars 0. */
    n = make_v2(b, sizeof b, fields, 0);
    TU_CHECK_STATUS(clvr_mesh_parse_bin(b, n, "none.bin", NULL, &m, &err), CLVR_OK, &err);
    TU_CHECK(m.num_fields == 0 && m.scalar_max == 0.0f);
    clvr_mesh_free(&m);
}

/* .series files (clvr-convert writes them for time series). */
static void test_series_files(void)
{
    char **paths = NULL;
    double *times = NULL;
    uint32_t n = 0;
    clvr_error err = {0};
    const char *good = "{\"file-series-version\": \"1.0\", \"files\": [{\"name\": \"a.0000.bin\", \"time\": 0.5},"
                       " {\"name\": \"/abs/b.bin\", \"time\": 2}]}";
    write_file(tmp_path("s.bin.series"), good, strlen(good));
    TU_CHECK(clvr_series_is(tmp_path("s.bin.series")) && !clvr_series_is("s.bin"));
    TU_CHECK_STATUS(clvr_series_read(tmp_path("s.bin.series"), &paths, &times, &n, &err), CLVR_OK, &err);
    TU_CHECK(n == 2 && times[0] == 0.5 && times[1] == 2.0);
    TU_CHECK(n == 2 && strcmp(paths[1], "/abs/b.bin") == 0 && strstr(paths[0], "/a.0000.bin") &&
             strncmp(paths[0], tmp_dir, strlen(tmp_dir)) == 0); /* relative to the series' folder */
    clvr_series_free(paths, times, n);
    const struct {
        const char *text, *says;
    } bad[] = {
        {"{\"files\": []}", "not a series file"},
        {"[1, 2]", "not a series file"},
        {"{\"files\": [{\"time\": 1}]}", "\"name\""},
        {"{\"files\": [{\"name\": 3}]}", "\"name\""},
        {"{\"files\": [", "bad.series"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        write_file(tmp_path("bad.series"), bad[i].text, strlen(bad[i].text));
        TU_CHECK(clvr_series_read(tmp_path("bad.series"), &paths, &times, &n, &err) != CLVR_OK);
        CHECK_MSG(err, "bad.series", bad[i].says);
        TU_CHECK(paths == NULL && n == 0);
    }
}

int main(void)
{
    snprintf(tmp_dir, sizeof tmp_dir, "/tmp/clvr_test_loaders.%ld", (long)getpid());
    if (mkdir(tmp_dir, 0755) != 0 && errno != EEXIST) {
        perror(tmp_dir);
        return 1;
    }
    test_bin_round_trip();
    test_bin_broken();
    test_files();
    test_vtk_files();
    test_vtk_synthetic();
    test_umesh();
    test_fields_vtk();
    test_vtk_polyhedra();
    test_series_files();
    test_fields_bin();
    test_fuzz_smoke();
    char cmd[600];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", tmp_dir);
    if (system(cmd) != 0) fprintf(stderr, "could not remove %s\n", tmp_dir);
    return tu_finish("test_loaders");
}
