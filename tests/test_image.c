/* Proves the image files: every writer round-trips through its reader
 * (EXR float exactly, PFM exactly without alpha, PNG within 8-bit sRGB
 * precision), the sRGB curve at known codes, half-float EXR input, and
 * atomic writes: a failed write (missing directory, target that is a
 * directory, file-size limit hit mid-file, read-only directory) reports the
 * path and the OS error, leaves no temporary file and keeps an older file. */
#include <dirent.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include <OpenEXR/ImfCRgbaFile.h>
#include <png.h>

#include "image.h"
#include "test_util.h"

static char g_dir[64];

static void path_in_dir(char *out, size_t size, const char *name) { snprintf(out, size, "%s/%s", g_dir, name); }

static float *random_image(uint32_t w, uint32_t h, float scale, uint64_t *rng)
{
    float *p = malloc(sizeof(float) * 4 * w * h);
    for (size_t i = 0; i < (size_t)w * h * 4; ++i) p[i] = tu_randf(rng) * ((i & 3) == 3 ? 1.0f : scale);
    return p;
}

/* Files named *.tmp.* left in the test directory. */
static int leftover_temps(void)
{
    int n = 0;
    DIR *d = opendir(g_dir);
    if (!d) return -1;
    for (struct dirent *e; (e = readdir(d));) n += strstr(e->d_name, ".tmp.") != NULL;
    closedir(d);
    return n;
}

static long file_bytes(const char *path, unsigned char **data)
{
    FILE *f = fopen(path, "rb");
    if (!f) return -1;
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    *data = malloc((size_t)n + 1);
    if (fread(*data, 1, (size_t)n, f) != (size_t)n) n = -1;
    fclose(f);
    return n;
}

static void test_srgb(void)
{
    TU_CHECK_EQ_U64(clvr_image_srgb_to_u8(0.0f), 0);
    TU_CHECK_EQ_U64(clvr_image_srgb_to_u8(1.0f), 255);
    TU_CHECK_EQ_U64(clvr_image_srgb_to_u8(0.5f), 188);       /* 1.055 * 0.5^(1/2.4) - 0.055 = 0.7354 */
    TU_CHECK_EQ_U64(clvr_image_srgb_to_u8(0.18f), 118);      /* middle grey: 0.4614 */
    TU_CHECK_EQ_U64(clvr_image_srgb_to_u8(0.0031308f), 10);  /* the knee: 0.04045 */
    TU_CHECK_EQ_U64(clvr_image_srgb_to_u8(0.001f), 3);       /* linear segment: 12.92 * 0.001 */
    TU_CHECK_EQ_U64(clvr_image_srgb_to_u8(0.21586f), 128);   /* sRGB 128/255 */
    TU_CHECK_EQ_U64(clvr_image_srgb_to_u8(7.0f), 255);       /* clamped */
    TU_CHECK_EQ_U64(clvr_image_srgb_to_u8(-1.0f), 0);
    TU_CHECK_EQ_U64(clvr_image_srgb_to_u8(NAN), 0);
    TU_CHECK_NEAR(clvr_image_srgb_decode(0.5f), 0.214041, 1e-6);
    TU_CHECK_NEAR(clvr_image_srgb_encode(0.0031308f), 0.04045, 1e-6);
    double worst = 0.0;
    for (int i = 0; i <= 1000; ++i) {
        float x = i / 1000.0f;
        worst = fmax(worst, fabs(clvr_image_srgb_decode(clvr_image_srgb_encode(x)) - x));
    }
    TU_CHECK_NEAR(worst, 0.0, 1e-6);
}

static void test_round_trips(void)
{
    uint64_t rng = 5;
    clvr_error err = {0};
    const uint32_t w = 37, h = 23; /* odd sizes: rows and chunks do not divide evenly */
    float *hdr = random_image(w, h, 50.0f, &rng);
    hdr[0] = -2.5f; /* negative and tiny values survive a float format */
    hdr[1] = 1e-30f;
    char p[256];
    clvr_image img;

    path_in_dir(p, sizeof p, "rt.exr");
    TU_CHECK_STATUS(clvr_image_write(p, w, h, hdr, &err), CLVR_OK, &err);
    TU_CHECK_STATUS(clvr_image_read(p, &img, &err), CLVR_OK, &err);
    TU_CHECK(img.width == w && img.height == h);
    if (img.rgba) TU_CHECK(memcmp(img.rgba, hdr, sizeof(float) * 4 * w * h) == 0); /* 32-bit float: exact */
    clvr_image_free(&img);
    /* The same file through OpenEXR's own RGBA interface (half): channel
     * names and row order as other tools see them. */
    ImfInputFile *in = ImfOpenInputFile(p);
    TU_CHECK(in != NULL);
    if (in) {
        int x0, y0, x1, y1;
        ImfHeaderDataWindow(ImfInputHeader(in), &x0, &y0, &x1, &y1);
        TU_CHECK(x0 == 0 && y0 == 0 && x1 == (int)w - 1 && y1 == (int)h - 1);
        ImfRgba *px = malloc(sizeof(ImfRgba) * w * h);
        ImfInputSetFrameBuffer(in, px, 1, w);
        TU_CHECK(ImfInputReadPixels(in, 0, (int)h - 1) != 0);
        double worst_rel = 0.0;
        for (size_t i = 1; i < (size_t)w * h; ++i) { /* pixel 0 holds the tiny/negative values */
            float v[4] = {ImfHalfToFloat(px[i].r), ImfHalfToFloat(px[i].g), ImfHalfToFloat(px[i].b),
                          ImfHalfToFloat(px[i].a)};
            for (int c = 0; c < 4; ++c)
                worst_rel = fmax(worst_rel, fabs(v[c] - hdr[4 * i + c]) / fmax(fabs(hdr[4 * i + c]), 1e-3));
        }
        TU_CHECK(worst_rel < 1e-3); /* half precision: 2^-11 */
        free(px);
        ImfCloseInputFile(in);
    }

    path_in_dir(p, sizeof p, "RT.PFM"); /* extensions are case-insensitive */
    TU_CHECK_STATUS(clvr_image_write(p, w, h, hdr, &err), CLVR_OK, &err);
    TU_CHECK_STATUS(clvr_image_read(p, &img, &err), CLVR_OK, &err);
    int pfm_bad = 0;
    for (size_t i = 0; img.rgba && i < (size_t)w * h; ++i)
        for (int c = 0; c < 4; ++c) pfm_bad += img.rgba[4 * i + c] != (c == 3 ? 1.0f : hdr[4 * i + c]);
    TU_CHECK_EQ_U64(pfm_bad, 0);
    clvr_image_free(&img);
    /* PFM layout: header, then the bottom row first, little-endian floats. */
    unsigned char *bytes = NULL;
    long n = file_bytes(p, &bytes);
    const char *hdr_text = "PF\n37 23\n-1.0\n";
    TU_CHECK_EQ_U64(n, strlen(hdr_text) + (size_t)w * h * 12);
    if (n > 0) {
        TU_CHECK(memcmp(bytes, hdr_text, strlen(hdr_text)) == 0);
        float first;
        memcpy(&first, bytes + strlen(hdr_text), 4);
        TU_CHECK_NEAR(first, hdr[(size_t)(h - 1) * w * 4], 0.0);
    }
    free(bytes);

    float *ldr = random_image(w, h, 1.2f, &rng); /* some values above 1: clamped */
    ldr[2] = NAN;
    path_in_dir(p, sizeof p, "rt.png");
    TU_CHECK_STATUS(clvr_image_write(p, w, h, ldr, &err), CLVR_OK, &err);
    TU_CHECK_STATUS(clvr_image_read(p, &img, &err), CLVR_OK, &err);
    double worst = 0.0;
    for (size_t i = 0; img.rgba && i < (size_t)w * h * 4; ++i) {
        float v = ldr[i] > 0.0f ? fminf(ldr[i], 1.0f) : 0.0f;
        /* PNG is opaque: alpha reads back as 1 whatever was written. */
        double e = (i & 3) == 3 ? fabs(img.rgba[i] - 1.0f)
                                : fabs(clvr_image_srgb_encode(img.rgba[i]) - clvr_image_srgb_encode(v));
        worst = fmax(worst, e);
    }
    printf("png round trip: worst error %.6f in sRGB units (half a code is %.6f)\n", worst, 0.5 / 255);
    TU_CHECK(worst <= 0.5 / 255 + 1e-5);
    clvr_image_free(&img);

    /* The stored bytes are the sRGB codes, and the file says sRGB. */
    float known[8] = {0.5f, 0.18f, 0.001f, 0.25f, 1.0f, 0.0f, 2.0f, 0.5f};
    path_in_dir(p, sizeof p, "codes.png");
    TU_CHECK_STATUS(clvr_image_write(p, 2, 1, known, &err), CLVR_OK, &err);
    png_image pi;
    memset(&pi, 0, sizeof pi);
    pi.version = PNG_IMAGE_VERSION;
    unsigned char px[8] = {0};
    if (png_image_begin_read_from_file(&pi, p)) {
        TU_CHECK(!(pi.flags & PNG_IMAGE_FLAG_COLORSPACE_NOT_sRGB));
        pi.format = PNG_FORMAT_RGBA;
        TU_CHECK(png_image_finish_read(&pi, NULL, px, 0, NULL));
    } else {
        TU_CHECK(0);
    }
    const unsigned char want[8] = {188, 118, 3, 255, 255, 0, 255, 255}; /* opaque */
    for (int i = 0; i < 8; ++i) TU_CHECK_EQ_U64(px[i], want[i]);
    free(hdr);
    free(ldr);
}

/* A half-float EXR written by ImfCRgbaFile reads back within half precision. */
static void test_half_exr(void)
{
    clvr_error err = {0};
    char p[256];
    path_in_dir(p, sizeof p, "half.exr");
    const int w = 5, h = 3;
    ImfRgba px[15];
    for (int i = 0; i < w * h; ++i) {
        ImfFloatToHalf(0.1f * i, &px[i].r);
        ImfFloatToHalf(1.0f, &px[i].g);
        ImfFloatToHalf(100.0f + i, &px[i].b);
        ImfFloatToHalf(0.5f, &px[i].a);
    }
    ImfHeader *hd = ImfNewHeader();
    ImfHeaderSetDataWindow(hd, 0, 0, w - 1, h - 1);
    ImfHeaderSetDisplayWindow(hd, 0, 0, w - 1, h - 1);
    ImfOutputFile *out = ImfOpenOutputFile(p, hd, IMF_WRITE_RGBA);
    ImfDeleteHeader(hd);
    if (!out) { fprintf(stderr, "ImfOpenOutputFile: %s\n", ImfErrorMessage()); TU_CHECK(0); return; }
    ImfOutputSetFrameBuffer(out, px, 1, (size_t)w);
    ImfOutputWritePixels(out, h);
    ImfCloseOutputFile(out);
    clvr_image img;
    TU_CHECK_STATUS(clvr_image_read(p, &img, &err), CLVR_OK, &err);
    if (img.rgba) {
        TU_CHECK_NEAR(img.rgba[4 * 7 + 0], 0.7, 0.7 * 1e-3);
        TU_CHECK_NEAR(img.rgba[4 * 7 + 1], 1.0, 0.0);
        TU_CHECK_NEAR(img.rgba[4 * 14 + 2], 114.0, 0.0);
        TU_CHECK_NEAR(img.rgba[4 * 14 + 3], 0.5, 0.0);
    }
    clvr_image_free(&img);
}

static void test_bad_inputs(void)
{
    clvr_error err = {0};
    clvr_image img;
    float px[4] = {0};
    TU_CHECK_STATUS(clvr_image_write("out.jpg", 1, 1, px, &err), CLVR_ERR_USAGE, &err);
    TU_CHECK(strstr(err.msg, "out.jpg") && strstr(err.msg, ".exr, .png, .pfm"));
    TU_CHECK_STATUS(clvr_image_write("dir.v2/noext", 1, 1, px, &err), CLVR_ERR_USAGE, &err);
    TU_CHECK_STATUS(clvr_image_write("x.png", 0, 1, px, &err), CLVR_ERR_USAGE, &err);
    char p[256];
    path_in_dir(p, sizeof p, "missing.pfm");
    TU_CHECK_STATUS(clvr_image_read(p, &img, &err), CLVR_ERR_IO, &err);
    path_in_dir(p, sizeof p, "short.pfm");
    FILE *f = fopen(p, "wb");
    fputs("PF\n4 4\n-1.0\n", f);
    fwrite(px, 4, 4, f);
    fclose(f);
    TU_CHECK_STATUS(clvr_image_read(p, &img, &err), CLVR_ERR_TRUNCATED, &err);
    TU_CHECK(img.rgba == NULL);
    f = fopen(p, "wb");
    fputs("P6\n4 4\n255\n", f);
    fclose(f);
    TU_CHECK_STATUS(clvr_image_read(p, &img, &err), CLVR_ERR_FORMAT, &err);
    f = fopen(p, "wb");
    fputs("PF\n4 -4\n-1.0\n", f);
    fclose(f);
    TU_CHECK_STATUS(clvr_image_read(p, &img, &err), CLVR_ERR_FORMAT, &err);
    path_in_dir(p, sizeof p, "notexr.exr");
    f = fopen(p, "wb");
    fputs("this is not an OpenEXR file at all", f);
    fclose(f);
    TU_CHECK(clvr_image_read(p, &img, &err) != CLVR_OK);
    TU_CHECK(strstr(err.msg, p) != NULL);
}

static void expect_write_fails(const char *path, uint32_t w, uint32_t h, const float *px, const char *os_error)
{
    clvr_error err = {0};
    TU_CHECK_STATUS(clvr_image_write(path, w, h, px, &err), CLVR_ERR_WRITE, &err);
    if (!strstr(err.msg, path) || (os_error && !strstr(err.msg, os_error))) {
        fprintf(stderr, "message for %s lacks the path or \"%s\": %s\n", path, os_error ? os_error : "", err.msg);
        TU_CHECK(0);
    }
}

static void test_atomic_writes(void)
{
    static const char *exts[3] = {"exr", "png", "pfm"};
    uint64_t rng = 77;
    clvr_error err = {0};
    char p[256];
    const uint32_t w = 256, h = 256;
    float *big = random_image(w, h, 1.0f, &rng); /* noise: EXR's ZIP cannot shrink it much */
    float small[4 * 4 * 4];
    for (int i = 0; i < 64; ++i) small[i] = 0.25f;
    for (int e = 0; e < 3; ++e) {
        /* Missing directory. */
        snprintf(p, sizeof p, "%s/no/such/dir/out.%s", g_dir, exts[e]);
        expect_write_fails(p, 4, 4, small, "No such file or directory");
        /* The target is a directory: the data are written, the rename fails. */
        snprintf(p, sizeof p, "%s/isdir.%s", g_dir, exts[e]);
        mkdir(p, 0755);
        expect_write_fails(p, 4, 4, small, NULL);
        struct stat st;
        TU_CHECK(stat(p, &st) == 0 && S_ISDIR(st.st_mode));
        rmdir(p);
        TU_CHECK_EQ_U64(leftover_temps(), 0);

        /* A full disk mid-file, simulated with the file-size limit: the older
         * file survives byte for byte and no temporary file remains. */
        snprintf(p, sizeof p, "%s/keep.%s", g_dir, exts[e]);
        TU_CHECK_STATUS(clvr_image_write(p, 4, 4, small, &err), CLVR_OK, &err);
        unsigned char *before = NULL, *after = NULL;
        long nb = file_bytes(p, &before);
        struct rlimit old, lim;
        getrlimit(RLIMIT_FSIZE, &old);
        lim = old;
        lim.rlim_cur = 4096;
        void (*prev)(int) = signal(SIGXFSZ, SIG_IGN);
        TU_CHECK(setrlimit(RLIMIT_FSIZE, &lim) == 0);
        expect_write_fails(p, w, h, big, "File too large");
        setrlimit(RLIMIT_FSIZE, &old);
        signal(SIGXFSZ, prev);
        long na = file_bytes(p, &after);
        TU_CHECK(nb > 0 && na == nb && memcmp(before, after, (size_t)nb) == 0);
        free(before);
        free(after);
        TU_CHECK_EQ_U64(leftover_temps(), 0);

        /* Once writable again, the file is replaced. */
        TU_CHECK_STATUS(clvr_image_write(p, w, h, big, &err), CLVR_OK, &err);
        clvr_image img;
        TU_CHECK_STATUS(clvr_image_read(p, &img, &err), CLVR_OK, &err);
        TU_CHECK(img.width == w && img.height == h);
        clvr_image_free(&img);
        unlink(p);
    }
    /* A directory that cannot hold the file, whoever runs the test (root,
     * as CI does, ignores permissions): a path under a regular file. */
    snprintf(p, sizeof p, "%s/plain.png", g_dir);
    TU_CHECK_STATUS(clvr_image_write(p, 4, 4, small, &err), CLVR_OK, &err);
    char under[300];
    snprintf(under, sizeof under, "%s/out.png", p);
    expect_write_fails(under, 4, 4, small, "Not a directory");
    unlink(p);
    TU_CHECK_EQ_U64(leftover_temps(), 0);
    /* Read-only directory: root ignores permissions, so only as a user. */
    if (geteuid() != 0) {
        char ro[128];
        snprintf(ro, sizeof ro, "%s/ro", g_dir);
        mkdir(ro, 0555);
        snprintf(p, sizeof p, "%s/out.png", ro);
        expect_write_fails(p, 4, 4, small, "Permission denied");
        rmdir(ro);
    } else {
        printf("read-only directory case not run as root (the path under a file above runs)\n");
    }
    free(big);
}

/* The tone curves at known values, their shape (monotonic, toe below the
 * identity, shoulder below 1 so nothing clips), exposure as a power of two,
 * PNG codes written with them, EXR and PFM left linear, transparent PNG's
 * alpha and straight colour, and numbered file names for --orbit. */
static void test_display(void)
{
    clvr_error err = {0};
    char p[256];
    /* ACES fit at 1.5 x: x = 1 -> 1.5 (2.51*1.5 + 0.03) / (1.5 (2.43*1.5 + 0.59) + 0.14) = 0.87678. */
    TU_CHECK_NEAR(clvr_image_tonemap(CLVR_TONEMAP_ACES, 1.0f), 0.87678, 1e-4);
    /* The fit reaches 1 where 0.08 y^2 - 0.56 y - 0.14 = 0, y = 7.2404, x = y / 1.5. */
    TU_CHECK(clvr_image_tonemap(CLVR_TONEMAP_ACES, 4.80f) < 1.0f);
    TU_CHECK_NEAR(clvr_image_tonemap(CLVR_TONEMAP_ACES, 4.84f), 1.0, 0.0);
    TU_CHECK_NEAR(clvr_image_tonemap(CLVR_TONEMAP_ACES, 0.0f), 0.0, 0.0);
    TU_CHECK_NEAR(clvr_image_tonemap(CLVR_TONEMAP_NONE, 0.5f), 0.5, 0.0);
    TU_CHECK_NEAR(clvr_image_tonemap(CLVR_TONEMAP_NONE, 3.0f), 1.0, 0.0);
    /* Hable at 3 x, normalised by its value at 11.2: white at x = 11.2 / 3. */
    TU_CHECK_NEAR(clvr_image_tonemap(CLVR_TONEMAP_FILMIC, 11.2f / 3.0f), 1.0, 1e-5);
    TU_CHECK(clvr_image_tonemap(CLVR_TONEMAP_FILMIC, 3.6f) < 1.0f);
    for (int t = CLVR_TONEMAP_ACES; t <= CLVR_TONEMAP_FILMIC; ++t) {
        float prev = 0.0f;
        int monotonic = 1;
        for (float x = 1e-4f; x < 1000.0f; x *= 1.1f) {
            float y = clvr_image_tonemap((clvr_tonemap)t, x);
            monotonic &= y >= prev && y <= 1.0f && (x > 3.6f || y < 1.0f);
            prev = y;
        }
        TU_CHECK(monotonic);
        TU_CHECK(clvr_image_tonemap((clvr_tonemap)t, 0.01f) < 0.01f * CLVR_TONEMAP_GAIN); /* toe */
        TU_CHECK_NEAR(clvr_image_tonemap((clvr_tonemap)t, INFINITY), 1.0, 0.0);
        TU_CHECK_NEAR(clvr_image_tonemap((clvr_tonemap)t, NAN), 0.0, 0.0);
    }
    TU_CHECK(clvr_tonemap_parse("aces") == CLVR_TONEMAP_ACES && clvr_tonemap_parse("filmic") == CLVR_TONEMAP_FILMIC);
    TU_CHECK(clvr_tonemap_parse("none") == CLVR_TONEMAP_NONE && clvr_tonemap_parse("ACES") == CLVR_TONEMAP_COUNT);

    /* PNG codes: exposure +1 under aces equals exposure 0 of twice the value. */
    float px[8] = {0.25f, 0.5f, 1.0f, 1.0f, 0.5f, 1.0f, 2.0f, 1.0f};
    clvr_image_display d = {1.0f, CLVR_TONEMAP_ACES, 0, NULL};
    path_in_dir(p, sizeof p, "tm.png");
    TU_CHECK_STATUS(clvr_image_write_display(p, 2, 1, px, &d, &err), CLVR_OK, &err);
    clvr_image img;
    TU_CHECK_STATUS(clvr_image_read(p, &img, &err), CLVR_OK, &err);
    for (int i = 0; img.rgba && i < 3; ++i) {
        uint8_t want = clvr_image_srgb_to_u8(clvr_image_tonemap(CLVR_TONEMAP_ACES, px[4 + i]));
        TU_CHECK_EQ_U64(clvr_image_srgb_to_u8(img.rgba[i]), want);
        TU_CHECK(clvr_image_srgb_to_u8(img.rgba[4 + i]) < 255); /* 2^1 * 2.0 is not clipped */
        TU_CHECK_NEAR(img.rgba[3], 1.0, 0.0);                   /* opaque */
    }
    clvr_image_free(&img);

    /* EXR and PFM ignore the display transform. */
    d.exposure_ev = 3.0f;
    d.transparent = 1;
    path_in_dir(p, sizeof p, "tm.exr");
    TU_CHECK_STATUS(clvr_image_write_display(p, 2, 1, px, &d, &err), CLVR_OK, &err);
    TU_CHECK_STATUS(clvr_image_read(p, &img, &err), CLVR_OK, &err);
    for (int i = 0; img.rgba && i < 8; ++i) TU_CHECK_NEAR(img.rgba[i], px[i], 0.0);
    clvr_image_free(&img);
    path_in_dir(p, sizeof p, "tm.pfm");
    TU_CHECK_STATUS(clvr_image_write_display(p, 2, 1, px, &d, &err), CLVR_OK, &err);
    TU_CHECK_STATUS(clvr_image_read(p, &img, &err), CLVR_OK, &err);
    for (int i = 0; img.rgba && i < 3; ++i) TU_CHECK_NEAR(img.rgba[4 + i], px[4 + i], 0.0);
    clvr_image_free(&img);

    /* Transparent PNG: alpha = a; colour = the premultiplied colour / a. */
    float pre[12] = {0.1f, 0.2f, 0.3f, 0.5f, 0.0f, 0.0f, 0.0f, 0.0f, 0.8f, 0.4f, 0.2f, 1.0f};
    clvr_image_display t = {0.0f, CLVR_TONEMAP_NONE, 1, NULL};
    path_in_dir(p, sizeof p, "alpha.png");
    TU_CHECK_STATUS(clvr_image_write_display(p, 3, 1, pre, &t, &err), CLVR_OK, &err);
    png_image pi;
    memset(&pi, 0, sizeof pi);
    pi.version = PNG_IMAGE_VERSION;
    unsigned char got[12] = {0};
    TU_CHECK(png_image_begin_read_from_file(&pi, p) && (pi.format & PNG_FORMAT_FLAG_ALPHA));
    pi.format = PNG_FORMAT_RGBA;
    TU_CHECK(png_image_finish_read(&pi, NULL, got, 0, NULL));
    const unsigned char want_rgba[12] = {clvr_image_srgb_to_u8(0.2f), clvr_image_srgb_to_u8(0.4f),
                                         clvr_image_srgb_to_u8(0.6f), 128, 0, 0, 0, 0,
                                         clvr_image_srgb_to_u8(0.8f), clvr_image_srgb_to_u8(0.4f),
                                         clvr_image_srgb_to_u8(0.2f), 255};
    for (int i = 0; i < 12; ++i) TU_CHECK_EQ_U64(got[i], want_rgba[i]);

    char name[64];
    TU_CHECK(clvr_image_numbered_path("out/a.png", 7, name, sizeof name) && !strcmp(name, "out/a.0007.png"));
    TU_CHECK(clvr_image_numbered_path("a.b/noext", 12345, name, sizeof name) && !strcmp(name, "a.b/noext.12345"));
    TU_CHECK(clvr_image_numbered_path(".hidden", 0, name, sizeof name) && !strcmp(name, ".hidden.0000"));
    TU_CHECK(!clvr_image_numbered_path("long-name.png", 1, name, 8));
}

static int popcount_glyph(char c)
{
    const uint8_t *g = clvr_image_glyph(c);
    int n = 0;
    for (int r = 0; g && r < 7; ++r)
        for (int b = 0; b < 5; ++b) n += g[r] >> b & 1;
    return n;
}

/* White pixels (255, 255, 255) in [x0, x1) x [y0, y1). */
static int white_in(const uint8_t *px, uint32_t ch, uint32_t w, int x0, int y0, int x1, int y1)
{
    int n = 0;
    for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) {
            const uint8_t *p = px + ((size_t)y * w + (size_t)x) * ch;
            n += p[0] == 255 && p[1] == 255 && p[2] == 255;
        }
    return n;
}

/* The legend: the font's lookups, a layout inside the image's bottom-left
 * corner, the bar's ends in the table's first and last colours, exactly the
 * glyphs' pixels of the name and of both range labels in white, the panel's
 * darkening and alpha, nothing drawn above the panel. */
static void test_legend(void)
{
    TU_CHECK(clvr_image_glyph('a') == clvr_image_glyph('A') && clvr_image_glyph(' ') == NULL);
    TU_CHECK(clvr_image_glyph('~') == clvr_image_glyph('?') && clvr_image_glyph('?') != NULL);
    TU_CHECK_EQ_U64(popcount_glyph('1'), 10);
    const float table[8] = {1.0f, 0.0f, 0.0f, 1.0f, 0.0f, 0.0f, 1.0f, 1.0f}; /* red -> blue */
    clvr_image_legend l = {table, 2, 0.0f, 1.0f, "Ab"};
    const uint32_t w = 200, h = 100;
    clvr_image_legend_layout o;
    clvr_image_legend_layout_of(w, h, &l, &o);
    TU_CHECK_EQ_U64(o.scale, 1);
    TU_CHECK(o.panel[0] >= 0 && o.panel[1] > (int32_t)h / 2 && o.panel[2] <= (int32_t)w && o.panel[3] <= (int32_t)h);
    TU_CHECK(o.bar[0] >= o.panel[0] && o.bar[2] <= o.panel[2] && o.bar[1] > o.title_y && o.labels_y > o.bar[3]);
    TU_CHECK(o.labels_y + 7 <= o.panel[3] && o.title_chars == 2);
    for (uint32_t ch = 3; ch <= 4; ++ch) {
        uint8_t *px = calloc((size_t)w * h * ch, 1);
        for (size_t i = 0; i < (size_t)w * h * ch; ++i) px[i] = ch == 4 && i % 4 == 3 ? 0 : 100;
        clvr_image_draw_legend(px, ch, w, h, &l);
        const uint8_t *left = px + ((size_t)o.bar[1] * w + (size_t)o.bar[0]) * ch;
        const uint8_t *right = px + ((size_t)o.bar[1] * w + (size_t)o.bar[2] - 1) * ch;
        TU_CHECK(left[0] == 255 && left[1] == 0 && left[2] == 0);
        TU_CHECK(right[0] == 0 && right[1] == 0 && right[2] == 255);
        TU_CHECK_EQ_U64(white_in(px, ch, w, o.title_x, o.title_y, o.title_x + 12, o.title_y + 7),
                        popcount_glyph('A') + popcount_glyph('B'));
        TU_CHECK_EQ_U64(white_in(px, ch, w, o.bar[0], o.labels_y, o.bar[0] + 6, o.labels_y + 7), popcount_glyph('0'));
        TU_CHECK_EQ_U64(white_in(px, ch, w, o.bar[2] - 5, o.labels_y, o.bar[2], o.labels_y + 7), popcount_glyph('1'));
        /* The panel's corner is darkened (RGB: 100 -> 40) or made 60% opaque (RGBA). */
        const uint8_t *corner = px + ((size_t)o.panel[1] * w + (size_t)o.panel[0]) * ch;
        if (ch == 3) TU_CHECK_EQ_U64(corner[0], 40);
        else TU_CHECK_EQ_U64(corner[3], 153);
        int touched = 0;
        for (size_t i = 0; i < (size_t)o.panel[1] * w * ch; ++i) touched += px[i] != (ch == 4 && i % 4 == 3 ? 0 : 100);
        TU_CHECK_EQ_U64(touched, 0);
        free(px);
    }
    /* A big image scales the font; a long name is cut to the room there is. */
    clvr_image_legend_layout_of(1024, 768, &l, &o);
    TU_CHECK_EQ_U64(o.scale, 3);
    l.name = "a-very-long-field-name-that-cannot-fit-into-a-small-image";
    clvr_image_legend_layout_of(64, 64, &l, &o);
    TU_CHECK(o.title_chars < strlen(l.name) && o.panel[2] <= 64);
}

static void remove_dir(void)
{
    DIR *d = opendir(g_dir);
    if (!d) return;
    char p[512];
    for (struct dirent *e; (e = readdir(d));) {
        if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, "..")) continue;
        snprintf(p, sizeof p, "%s/%s", g_dir, e->d_name);
        unlink(p);
    }
    closedir(d);
    rmdir(g_dir);
}

int main(void)
{
    snprintf(g_dir, sizeof g_dir, "/tmp/clvr_test_image_XXXXXX");
    if (!mkdtemp(g_dir)) { perror("mkdtemp"); return 1; }
    test_srgb();
    test_round_trips();
    test_half_exr();
    test_bad_inputs();
    test_atomic_writes();
    test_display();
    test_legend();
    remove_dir();
    return tu_finish("test_image");
}
