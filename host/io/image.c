/* image.c: image files: OpenEXR (float, core C API), PNG (sRGB, libpng's
 * simplified API) and PFM, each written atomically through a temporary file
 * in the target's directory (see image.h). */
#include "image.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <unistd.h>

#include <OpenEXR/openexr.h>
#include <png.h>

/* ------------------------------------------------------------ basics */

clvr_status clvr_image_alloc(clvr_image *img, uint32_t width, uint32_t height, clvr_error *err)
{
    memset(img, 0, sizeof *img);
    if (width == 0 || height == 0 || width > CLVR_IMAGE_MAX_DIM || height > CLVR_IMAGE_MAX_DIM)
        return clvr_error_set(err, CLVR_ERR_USAGE, "image size %ux%u: expected 1..%u pixels per side", width, height,
                              CLVR_IMAGE_MAX_DIM);
    img->rgba = calloc((size_t)width * height * 4, sizeof(float));
    if (!img->rgba)
        return clvr_error_set(err, CLVR_ERR_NO_MEMORY, "out of memory for a %ux%u image", width, height);
    img->width = width;
    img->height = height;
    return CLVR_OK;
}

void clvr_image_free(clvr_image *img)
{
    if (!img) return;
    free(img->rgba);
    memset(img, 0, sizeof *img);
}

const char *clvr_image_formats(void) { return "exr, png, pfm"; }

float clvr_image_srgb_encode(float c)
{
    return c > 0.0031308f ? 1.055f * powf(c, 1.0f / 2.4f) - 0.055f : 12.92f * c;
}

float clvr_image_srgb_decode(float c) { return c > 0.04045f ? powf((c + 0.055f) / 1.055f, 2.4f) : c / 12.92f; }

uint8_t clvr_image_srgb_to_u8(float c)
{
    c = c > 0.0f ? (c < 1.0f ? c : 1.0f) : 0.0f; /* NaN -> 0 */
    return (uint8_t)lrintf(clvr_image_srgb_encode(c) * 255.0f);
}

typedef enum { FMT_NONE, FMT_EXR, FMT_PNG, FMT_PFM } image_format;

static image_format format_of(const char *path)
{
    const char *slash = strrchr(path, '/');
    const char *dot = strrchr(slash ? slash : path, '.');
    if (!dot) return FMT_NONE;
    if (!strcasecmp(dot, ".exr")) return FMT_EXR;
    if (!strcasecmp(dot, ".png")) return FMT_PNG;
    if (!strcasecmp(dot, ".pfm")) return FMT_PFM;
    return FMT_NONE;
}

static int little_endian(void)
{
    const uint16_t one = 1;
    uint8_t b;
    memcpy(&b, &one, 1);
    return b == 1;
}

static void bswap32(void *p)
{
    uint8_t *b = p, t;
    t = b[0]; b[0] = b[3]; b[3] = t;
    t = b[1]; b[1] = b[2]; b[2] = t;
}

/* ------------------------------------------------------------ atomic files */

static char *temp_path_for(const char *path)
{
    size_t n = strlen(path) + 32;
    char *t = malloc(n);
    if (t) snprintf(t, n, "%s.tmp.%ld", path, (long)getpid());
    return t;
}

static clvr_status write_failed(const char *path, const char *tmp, const char *what, int code, clvr_error *err)
{
    if (tmp) unlink(tmp);
    return clvr_error_set(err, CLVR_ERR_WRITE, "cannot write image %s: %s%s%s", path, what ? what : "",
                          what && code ? ": " : "", code ? strerror(code) : "");
}

/* Flushes, syncs and closes f; on success renames tmp onto path. Removes tmp
 * on any failure. */
static clvr_status close_and_commit(FILE *f, const char *tmp, const char *path, clvr_error *err)
{
    int code = 0;
    if (fflush(f) != 0 || ferror(f)) code = errno ? errno : EIO;
    if (!code && fsync(fileno(f)) != 0 && errno != EINVAL) code = errno;
    if (fclose(f) != 0 && !code) code = errno ? errno : EIO;
    if (code) return write_failed(path, tmp, "writing failed", code, err);
    if (rename(tmp, path) != 0) return write_failed(path, tmp, "cannot replace it", errno, err);
    return CLVR_OK;
}

static clvr_status open_temp(const char *path, char **tmp, FILE **f, clvr_error *err)
{
    *tmp = temp_path_for(path);
    if (!*tmp) return clvr_error_set(err, CLVR_ERR_NO_MEMORY, "out of memory writing %s", path);
    errno = 0;
    *f = fopen(*tmp, "wb");
    if (!*f) {
        int code = errno;
        clvr_status s = write_failed(path, NULL, "cannot create a temporary file there", code, err);
        free(*tmp);
        *tmp = NULL;
        return s;
    }
    return CLVR_OK;
}

/* ------------------------------------------------------------ PFM */

static clvr_status write_pfm(const char *path, uint32_t w, uint32_t h, const float *rgba, clvr_error *err)
{
    char *tmp;
    FILE *f;
    clvr_status s = open_temp(path, &tmp, &f, err);
    if (s != CLVR_OK) return s;
    float *row = malloc(sizeof(float) * 3 * w);
    if (!row) {
        fclose(f);
        unlink(tmp);
        free(tmp);
        return clvr_error_set(err, CLVR_ERR_NO_MEMORY, "out of memory writing %s", path);
    }
    int ok = fprintf(f, "PF\n%u %u\n-1.0\n", w, h) > 0;
    int le = little_endian();
    /* PFM stores the bottom row first. */
    for (uint32_t y = 0; ok && y < h; ++y) {
        const float *src = rgba + (size_t)(h - 1 - y) * w * 4;
        for (uint32_t x = 0; x < w; ++x)
            for (int c = 0; c < 3; ++c) {
                row[3 * x + c] = src[4 * x + c];
                if (!le) bswap32(&row[3 * x + c]);
            }
        ok = fwrite(row, sizeof(float) * 3, w, f) == w;
    }
    free(row);
    if (!ok) {
        int code = errno ? errno : EIO;
        fclose(f);
        s = write_failed(path, tmp, "writing failed", code, err);
    } else {
        s = close_and_commit(f, tmp, path, err);
    }
    free(tmp);
    return s;
}

/* Reads the next whitespace-delimited header token of a PFM. */
static int pfm_token(FILE *f, char *buf, size_t size)
{
    int c;
    size_t n = 0;
    while ((c = fgetc(f)) != EOF && (c == ' ' || c == '\t' || c == '\r' || c == '\n')) {}
    while (c != EOF && !(c == ' ' || c == '\t' || c == '\r' || c == '\n')) {
        if (n + 1 >= size) return 0;
        buf[n++] = (char)c;
        c = fgetc(f);
    }
    buf[n] = '\0';
    /* c is the single whitespace byte that ends the token (consumed). */
    return n > 0 && c != EOF;
}

static clvr_status read_pfm(const char *path, clvr_image *out, clvr_error *err)
{
    FILE *f = fopen(path, "rb");
    if (!f) return clvr_error_set(err, CLVR_ERR_IO, "cannot open %s: %s", path, strerror(errno));
    char t[4][32];
    clvr_status s = CLVR_OK;
    float *row = NULL;
    for (int i = 0; i < 4; ++i)
        if (!pfm_token(f, t[i], sizeof t[i])) {
            s = clvr_error_set(err, CLVR_ERR_FORMAT, "%s: bad PFM header (expected \"PF|Pf width height scale\")", path);
            goto cleanup;
        }
    int chans = !strcmp(t[0], "PF") ? 3 : !strcmp(t[0], "Pf") ? 1 : 0;
    char *e1, *e2, *e3;
    unsigned long w = strtoul(t[1], &e1, 10), h = strtoul(t[2], &e2, 10);
    double scale = strtod(t[3], &e3);
    if (!chans || *e1 || *e2 || *e3 || w == 0 || h == 0 || w > CLVR_IMAGE_MAX_DIM || h > CLVR_IMAGE_MAX_DIM ||
        scale == 0.0 || !isfinite(scale)) {
        s = clvr_error_set(err, CLVR_ERR_FORMAT, "%s: bad PFM header \"%s %s %s %s\"", path, t[0], t[1], t[2], t[3]);
        goto cleanup;
    }
    s = clvr_image_alloc(out, (uint32_t)w, (uint32_t)h, err);
    if (s != CLVR_OK) goto cleanup;
    row = malloc(sizeof(float) * chans * w);
    if (!row) { s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "out of memory reading %s", path); goto cleanup; }
    int swap = (scale < 0.0) != little_endian();
    for (unsigned long y = 0; y < h; ++y) {
        if (fread(row, sizeof(float) * chans, w, f) != w) {
            s = clvr_error_set(err, CLVR_ERR_TRUNCATED, "%s: PFM data ends in row %lu of %lu", path, y, h);
            goto cleanup;
        }
        float *dst = out->rgba + (size_t)(h - 1 - y) * w * 4;
        for (unsigned long x = 0; x < w; ++x) {
            for (int c = 0; c < chans; ++c)
                if (swap) bswap32(&row[chans * x + c]);
            for (int c = 0; c < 3; ++c) dst[4 * x + c] = row[chans * x + (chans == 3 ? c : 0)];
            dst[4 * x + 3] = 1.0f;
        }
    }
cleanup:
    free(row);
    fclose(f);
    if (s != CLVR_OK) clvr_image_free(out);
    return s;
}

/* ------------------------------------------------------------ PNG */

const char *clvr_tonemap_name(clvr_tonemap t)
{
    static const char *names[CLVR_TONEMAP_COUNT] = {"none", "aces", "filmic"};
    return (unsigned)t < CLVR_TONEMAP_COUNT ? names[t] : "?";
}

clvr_tonemap clvr_tonemap_parse(const char *name)
{
    for (int t = 0; t < CLVR_TONEMAP_COUNT; ++t)
        if (name && !strcmp(name, clvr_tonemap_name((clvr_tonemap)t))) return (clvr_tonemap)t;
    return CLVR_TONEMAP_COUNT;
}

/* Hable's operator without the white-point normalisation. */
static float hable(float x)
{
    const float a = 0.15f, b = 0.50f, c = 0.10f, d = 0.20f, e = 0.02f, f = 0.30f;
    return (x * (a * x + c * b) + d * e) / (x * (a * x + b) + d * f) - e / f;
}

float clvr_image_tonemap(clvr_tonemap t, float x)
{
    if (!(x > 0.0f)) return 0.0f; /* NaN, negative, zero */
    float y;
    switch (t) {
    case CLVR_TONEMAP_ACES:
        x *= CLVR_TONEMAP_GAIN;
        y = isinf(x) ? 1.0f : x * (2.51f * x + 0.03f) / (x * (2.43f * x + 0.59f) + 0.14f);
        break;
    case CLVR_TONEMAP_FILMIC:
        x *= CLVR_TONEMAP_GAIN * 2.0f; /* Hable's exposure bias */
        y = isinf(x) ? 1.0f : hable(x) / hable(11.2f);
        break;
    default: y = x; break;
    }
    return y < 1.0f ? y : 1.0f;
}

/* ------------------------------------------------------------ legend */

/* A 5x7 font of the characters a field name and a number need (digits,
 * upper case, punctuation); rows top to bottom, bit 4 the leftmost column.
 * Drawn after the classic 5x7 LCD character sets. */
static const struct {
    char c;
    uint8_t rows[7];
} font5x7[] = {
    {'0', {0x0e, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0e}},
    {'1', {0x04, 0x0c, 0x04, 0x04, 0x04, 0x04, 0x0e}},
    {'2', {0x0e, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1f}},
    {'3', {0x1f, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0e}},
    {'4', {0x02, 0x06, 0x0a, 0x12, 0x1f, 0x02, 0x02}},
    {'5', {0x1f, 0x10, 0x1e, 0x01, 0x01, 0x11, 0x0e}},
    {'6', {0x06, 0x08, 0x10, 0x1e, 0x11, 0x11, 0x0e}},
    {'7', {0x1f, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08}},
    {'8', {0x0e, 0x11, 0x11, 0x0e, 0x11, 0x11, 0x0e}},
    {'9', {0x0e, 0x11, 0x11, 0x0f, 0x01, 0x02, 0x0c}},
    {'A', {0x0e, 0x11, 0x11, 0x1f, 0x11, 0x11, 0x11}},
    {'B', {0x1e, 0x11, 0x11, 0x1e, 0x11, 0x11, 0x1e}},
    {'C', {0x0e, 0x11, 0x10, 0x10, 0x10, 0x11, 0x0e}},
    {'D', {0x1c, 0x12, 0x11, 0x11, 0x11, 0x12, 0x1c}},
    {'E', {0x1f, 0x10, 0x10, 0x1e, 0x10, 0x10, 0x1f}},
    {'F', {0x1f, 0x10, 0x10, 0x1e, 0x10, 0x10, 0x10}},
    {'G', {0x0e, 0x11, 0x10, 0x17, 0x11, 0x11, 0x0f}},
    {'H', {0x11, 0x11, 0x11, 0x1f, 0x11, 0x11, 0x11}},
    {'I', {0x0e, 0x04, 0x04, 0x04, 0x04, 0x04, 0x0e}},
    {'J', {0x07, 0x02, 0x02, 0x02, 0x02, 0x12, 0x0c}},
    {'K', {0x11, 0x12, 0x14, 0x18, 0x14, 0x12, 0x11}},
    {'L', {0x10, 0x10, 0x10, 0x10, 0x10, 0x10, 0x1f}},
    {'M', {0x11, 0x1b, 0x15, 0x15, 0x11, 0x11, 0x11}},
    {'N', {0x11, 0x11, 0x19, 0x15, 0x13, 0x11, 0x11}},
    {'O', {0x0e, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0e}},
    {'P', {0x1e, 0x11, 0x11, 0x1e, 0x10, 0x10, 0x10}},
    {'Q', {0x0e, 0x11, 0x11, 0x11, 0x15, 0x12, 0x0d}},
    {'R', {0x1e, 0x11, 0x11, 0x1e, 0x14, 0x12, 0x11}},
    {'S', {0x0f, 0x10, 0x10, 0x0e, 0x01, 0x01, 0x1e}},
    {'T', {0x1f, 0x04, 0x04, 0x04, 0x04, 0x04, 0x04}},
    {'U', {0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0e}},
    {'V', {0x11, 0x11, 0x11, 0x11, 0x11, 0x0a, 0x04}},
    {'W', {0x11, 0x11, 0x11, 0x15, 0x15, 0x15, 0x0a}},
    {'X', {0x11, 0x11, 0x0a, 0x04, 0x0a, 0x11, 0x11}},
    {'Y', {0x11, 0x11, 0x0a, 0x04, 0x04, 0x04, 0x04}},
    {'Z', {0x1f, 0x01, 0x02, 0x04, 0x08, 0x10, 0x1f}},
    {'.', {0x00, 0x00, 0x00, 0x00, 0x00, 0x0c, 0x0c}},
    {'-', {0x00, 0x00, 0x00, 0x1f, 0x00, 0x00, 0x00}},
    {'+', {0x00, 0x04, 0x04, 0x1f, 0x04, 0x04, 0x00}},
    {':', {0x00, 0x0c, 0x0c, 0x00, 0x0c, 0x0c, 0x00}},
    {'_', {0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x1f}},
    {'(', {0x02, 0x04, 0x08, 0x08, 0x08, 0x04, 0x02}},
    {')', {0x08, 0x04, 0x02, 0x02, 0x02, 0x04, 0x08}},
    {'/', {0x00, 0x01, 0x02, 0x04, 0x08, 0x10, 0x00}},
    {',', {0x00, 0x00, 0x00, 0x00, 0x0c, 0x04, 0x08}},
    {'=', {0x00, 0x00, 0x1f, 0x00, 0x1f, 0x00, 0x00}},
    {'%', {0x18, 0x19, 0x02, 0x04, 0x08, 0x13, 0x03}},
    {'[', {0x0e, 0x08, 0x08, 0x08, 0x08, 0x08, 0x0e}},
    {']', {0x0e, 0x02, 0x02, 0x02, 0x02, 0x02, 0x0e}},
    {'?', {0x0e, 0x11, 0x01, 0x02, 0x04, 0x00, 0x04}},
};

const uint8_t *clvr_image_glyph(char c)
{
    if (c == ' ') return NULL;
    if (c >= 'a' && c <= 'z') c = (char)(c - 'a' + 'A');
    for (size_t i = 0; i < sizeof font5x7 / sizeof font5x7[0]; ++i)
        if (font5x7[i].c == c) return font5x7[i].rows;
    return clvr_image_glyph('?');
}

static const char *legend_name(const clvr_image_legend *l) { return l->name && *l->name ? l->name : "scalar"; }

void clvr_image_legend_layout_of(uint32_t w, uint32_t h, const clvr_image_legend *l, clvr_image_legend_layout *o)
{
    memset(o, 0, sizeof *o);
    uint32_t m = w < h ? w : h;
    const int32_t s = (int32_t)(m / 256 > 1 ? m / 256 : 1);
    const int32_t pad = 3 * s, margin = 4 * s, cell = 6 * s;
    int32_t room = (int32_t)w - 2 * margin - 2 * pad; /* panel contents' widest */
    if (room < cell) room = cell;
    int32_t bar_w = 160 * s < room ? 160 * s : room;
    size_t n = strlen(legend_name(l));
    uint32_t fit = (uint32_t)(room / cell);
    o->title_chars = n < fit ? (uint32_t)n : fit;
    int32_t title_w = (int32_t)o->title_chars * cell - s;
    int32_t inner_w = bar_w > title_w ? bar_w : title_w;
    int32_t panel_h = 2 * pad + 7 * s + 3 * s + 8 * s + 3 * s + 7 * s;
    o->scale = (uint32_t)s;
    o->panel[0] = margin;
    o->panel[3] = (int32_t)h - margin;
    o->panel[1] = o->panel[3] - panel_h;
    o->panel[2] = margin + 2 * pad + inner_w;
    o->title_x = margin + pad;
    o->title_y = o->panel[1] + pad;
    o->bar[0] = margin + pad;
    o->bar[1] = o->title_y + 7 * s + 3 * s;
    o->bar[2] = o->bar[0] + bar_w;
    o->bar[3] = o->bar[1] + 8 * s;
    o->labels_y = o->bar[3] + 3 * s;
}

static void put_px(uint8_t *px, uint32_t ch, uint32_t w, uint32_t h, int32_t x, int32_t y, const uint8_t rgb[3])
{
    if (x < 0 || y < 0 || (uint32_t)x >= w || (uint32_t)y >= h) return;
    uint8_t *p = px + ((size_t)y * w + (size_t)x) * ch;
    memcpy(p, rgb, 3);
    if (ch == 4) p[3] = 255;
}

static void draw_text(uint8_t *px, uint32_t ch, uint32_t w, uint32_t h, int32_t x, int32_t y, int32_t s,
                      const char *text, size_t n)
{
    static const uint8_t white[3] = {255, 255, 255};
    for (size_t i = 0; i < n; ++i, x += 6 * s) {
        const uint8_t *g = clvr_image_glyph(text[i]);
        for (int32_t r = 0; g && r < 7; ++r)
            for (int32_t c = 0; c < 5; ++c)
                if (g[r] >> (4 - c) & 1)
                    for (int32_t dy = 0; dy < s; ++dy)
                        for (int32_t dx = 0; dx < s; ++dx) put_px(px, ch, w, h, x + c * s + dx, y + r * s + dy, white);
    }
}

void clvr_image_draw_legend(uint8_t *px, uint32_t ch, uint32_t w, uint32_t h, const clvr_image_legend *l)
{
    clvr_image_legend_layout o;
    clvr_image_legend_layout_of(w, h, l, &o);
    const int32_t s = (int32_t)o.scale;
    /* The panel: 60% black over the image (in sRGB codes, as UI blending is). */
    for (int32_t y = o.panel[1] > 0 ? o.panel[1] : 0; y < o.panel[3] && y < (int32_t)h; ++y)
        for (int32_t x = o.panel[0]; x < o.panel[2] && x < (int32_t)w; ++x) {
            uint8_t *p = px + ((size_t)y * w + (size_t)x) * ch;
            if (ch == 4) {
                /* Black at 0.6 over a straight-alpha pixel: a' = 0.6 + 0.4 a, c' = 0.4 a c / a'. */
                float a = p[3] / 255.0f, a2 = 0.6f + 0.4f * a;
                for (int c = 0; c < 3; ++c) p[c] = (uint8_t)lrintf(0.4f * a * p[c] / a2);
                p[3] = (uint8_t)lrintf(a2 * 255.0f);
            } else {
                for (int c = 0; c < 3; ++c) p[c] = (uint8_t)lrintf(0.4f * p[c]);
            }
        }
    /* The bar: entry i of the table at column i * (entries - 1) / (width - 1). */
    int32_t bw = o.bar[2] - o.bar[0];
    for (int32_t x = 0; x < bw && l->entries; ++x) {
        uint32_t e = bw > 1 ? (uint32_t)lrintf((float)x * (float)(l->entries - 1) / (float)(bw - 1)) : 0;
        uint8_t rgb[3];
        for (int c = 0; c < 3; ++c) rgb[c] = clvr_image_srgb_to_u8(l->table[4 * (size_t)e + c]);
        for (int32_t y = o.bar[1]; y < o.bar[3]; ++y) put_px(px, ch, w, h, o.bar[0] + x, y, rgb);
    }
    draw_text(px, ch, w, h, o.title_x, o.title_y, s, legend_name(l), o.title_chars);
    char lo[32], hi[32];
    snprintf(lo, sizeof lo, "%.4g", (double)l->lo);
    snprintf(hi, sizeof hi, "%.4g", (double)l->hi);
    draw_text(px, ch, w, h, o.bar[0], o.labels_y, s, lo, strlen(lo));
    int32_t hi_w = (int32_t)strlen(hi) * 6 * s - s;
    draw_text(px, ch, w, h, o.bar[2] - hi_w, o.labels_y, s, hi, strlen(hi));
}

/* One 8-bit code of a display-linear value in [0, 1]. */
static uint8_t display_to_u8(float y) { return (uint8_t)lrintf(clvr_image_srgb_encode(y) * 255.0f); }

static clvr_status write_png(const char *path, uint32_t w, uint32_t h, const float *rgba,
                             const clvr_image_display *d, clvr_error *err)
{
    size_t n = (size_t)w * h;
    const int alpha = d && d->transparent;
    const int ch = alpha ? 4 : 3;
    const clvr_tonemap tm = d ? d->tonemap : CLVR_TONEMAP_NONE;
    const float gain = d ? exp2f(d->exposure_ev) : 1.0f;
    /* Opaque RGB by default: r g b already hold the background seen through
     * the volume, so an alpha channel would make viewers composite it twice.
     * Transparent: the colour was rendered over black (premultiplied) and PNG
     * wants it straight, so it is divided by alpha before the tone curve. */
    uint8_t *px = malloc(n * (size_t)ch);
    if (!px) return clvr_error_set(err, CLVR_ERR_NO_MEMORY, "out of memory writing %s", path);
    for (size_t i = 0; i < n; ++i) {
        float scale = gain;
        if (alpha) {
            float a = rgba[4 * i + 3];
            a = a > 0.0f ? (a < 1.0f ? a : 1.0f) : 0.0f; /* NaN -> 0 */
            px[4 * i + 3] = (uint8_t)lrintf(a * 255.0f);
            /* Below half a code the pixel is transparent and its colour moot. */
            scale = a >= 0.5f / 255.0f ? gain / a : 0.0f;
        }
        for (int c = 0; c < 3; ++c) {
            float x = rgba[4 * i + c] * scale;
            px[(size_t)ch * i + c] = display_to_u8(clvr_image_tonemap(tm, x));
        }
    }
    if (d && d->legend) clvr_image_draw_legend(px, (uint32_t)ch, w, h, d->legend);
    char *tmp;
    FILE *f;
    clvr_status s = open_temp(path, &tmp, &f, err);
    if (s != CLVR_OK) { free(px); return s; }
    png_image img;
    memset(&img, 0, sizeof img);
    img.version = PNG_IMAGE_VERSION;
    img.width = w;
    img.height = h;
    img.format = alpha ? PNG_FORMAT_RGBA : PNG_FORMAT_RGB; /* 8-bit, sRGB-encoded; alpha straight */
    errno = 0;
    int ok = png_image_write_to_stdio(&img, f, 0, px, 0, NULL);
    free(px);
    if (!ok) {
        int code = errno;
        char what[160];
        snprintf(what, sizeof what, "libpng: %s", img.message);
        png_image_free(&img);
        fclose(f);
        s = write_failed(path, tmp, what, code, err);
    } else {
        s = close_and_commit(f, tmp, path, err);
    }
    free(tmp);
    return s;
}

static clvr_status read_png(const char *path, clvr_image *out, clvr_error *err)
{
    png_image img;
    memset(&img, 0, sizeof img);
    img.version = PNG_IMAGE_VERSION;
    if (!png_image_begin_read_from_file(&img, path))
        return clvr_error_set(err, CLVR_ERR_FORMAT, "cannot read PNG %s: %s", path, img.message);
    img.format = PNG_FORMAT_RGBA;
    clvr_status s = clvr_image_alloc(out, img.width, img.height, err);
    uint8_t *px = s == CLVR_OK ? malloc(PNG_IMAGE_SIZE(img)) : NULL;
    if (s == CLVR_OK && !px) s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "out of memory reading %s", path);
    if (s != CLVR_OK) {
        png_image_free(&img);
        clvr_image_free(out);
        return s;
    }
    if (!png_image_finish_read(&img, NULL, px, 0, NULL)) {
        s = clvr_error_set(err, CLVR_ERR_FORMAT, "cannot read PNG %s: %s", path, img.message);
        clvr_image_free(out);
    } else {
        size_t n = (size_t)out->width * out->height;
        for (size_t i = 0; i < n; ++i) {
            for (int c = 0; c < 3; ++c) out->rgba[4 * i + c] = clvr_image_srgb_decode(px[4 * i + c] / 255.0f);
            out->rgba[4 * i + 3] = px[4 * i + 3] / 255.0f;
        }
    }
    png_image_free(&img);
    free(px);
    return s;
}

/* ------------------------------------------------------------ OpenEXR */

/* The core library reports errors through a callback; keep the last one. */
typedef struct exr_log {
    char msg[256];
} exr_log;

static void exr_on_error(exr_const_context_t ctxt, exr_result_t code, const char *msg)
{
    void *ud = NULL;
    if (ctxt && exr_get_user_data(ctxt, &ud) == EXR_ERR_SUCCESS && ud) {
        exr_log *log = ud;
        snprintf(log->msg, sizeof log->msg, "%s (%s)", msg ? msg : "", exr_get_error_code_as_string(code));
    }
}

static const char *exr_message(const exr_log *log, exr_result_t rv)
{
    return log->msg[0] ? log->msg : exr_get_default_error_message(rv);
}

static clvr_status write_exr(const char *path, uint32_t w, uint32_t h, const float *rgba, clvr_error *err)
{
    char *tmp = temp_path_for(path);
    if (!tmp) return clvr_error_set(err, CLVR_ERR_NO_MEMORY, "out of memory writing %s", path);
    exr_log log = {{0}};
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = exr_on_error;
    init.user_data = &log;
    exr_context_t ctx = NULL;
    exr_encode_pipeline_t enc = EXR_ENCODE_PIPELINE_INITIALIZER;
    int enc_ready = 0, part = 0, lines = 1;
    const char *step = "cannot create a temporary file there";
    clvr_status s = CLVR_OK;
    errno = 0;
    exr_result_t rv = exr_start_write(&ctx, tmp, EXR_WRITE_FILE_DIRECTLY, &init);
    int code = errno;
#define EXR_STEP(what, call)                                                                                          \
    do {                                                                                                              \
        step = what;                                                                                                  \
        errno = 0;                                                                                                    \
        rv = (call);                                                                                                  \
        code = errno;                                                                                                 \
        if (rv != EXR_ERR_SUCCESS) goto fail;                                                                         \
    } while (0)
    if (rv != EXR_ERR_SUCCESS) goto fail;
    EXR_STEP("OpenEXR header", exr_add_part(ctx, "rgba", EXR_STORAGE_SCANLINE, &part));
    EXR_STEP("OpenEXR header", exr_initialize_required_attr_simple(ctx, part, (int32_t)w, (int32_t)h,
                                                                    EXR_COMPRESSION_ZIP));
    static const char *names[4] = {"R", "G", "B", "A"};
    for (int c = 0; c < 4; ++c)
        EXR_STEP("OpenEXR channels",
                 exr_add_channel(ctx, part, names[c], EXR_PIXEL_FLOAT, EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1));
    EXR_STEP("writing the OpenEXR header", exr_write_header(ctx));
    EXR_STEP("OpenEXR chunk size", exr_get_scanlines_per_chunk(ctx, part, &lines));
    for (int32_t y = 0; y < (int32_t)h; y += lines) {
        exr_chunk_info_t ci;
        EXR_STEP("writing OpenEXR data", exr_write_scanline_chunk_info(ctx, part, y, &ci));
        if (!enc_ready) EXR_STEP("OpenEXR encoder", exr_encoding_initialize(ctx, part, &ci, &enc));
        else EXR_STEP("OpenEXR encoder", exr_encoding_update(ctx, part, &ci, &enc));
        for (int c = 0; c < enc.channel_count; ++c) {
            exr_coding_channel_info_t *ch = &enc.channels[c];
            int k = ch->channel_name[0] == 'R' ? 0 : ch->channel_name[0] == 'G' ? 1 : ch->channel_name[0] == 'B' ? 2 : 3;
            ch->encode_from_ptr = (const uint8_t *)(rgba + ((size_t)(ci.start_y) * w) * 4 + k);
            ch->user_pixel_stride = 4 * sizeof(float);
            ch->user_line_stride = (int32_t)(4 * sizeof(float) * w);
            ch->user_data_type = EXR_PIXEL_FLOAT;
            ch->user_bytes_per_element = sizeof(float);
        }
        if (!enc_ready) EXR_STEP("OpenEXR encoder", exr_encoding_choose_default_routines(ctx, part, &enc));
        enc_ready = 1;
        EXR_STEP("writing OpenEXR data", exr_encoding_run(ctx, part, &enc));
    }
#undef EXR_STEP
    if (enc_ready) exr_encoding_destroy(ctx, &enc);
    enc_ready = 0;
    step = "finishing the OpenEXR file";
    errno = 0;
    rv = exr_finish(&ctx);
    code = errno;
    if (rv != EXR_ERR_SUCCESS) goto fail;
    /* The library wrote through its own descriptor: sync by reopening, so the
     * rename below never exposes an unwritten file after a crash. */
    {
        int fd = open(tmp, O_RDONLY);
        if (fd < 0 || fsync(fd) != 0) {
            code = errno;
            if (fd >= 0) close(fd);
            s = write_failed(path, tmp, "flushing failed", code, err);
            free(tmp);
            return s;
        }
        close(fd);
    }
    if (rename(tmp, path) != 0) s = write_failed(path, tmp, "cannot replace it", errno, err);
    free(tmp);
    return s;
fail:
    if (enc_ready) exr_encoding_destroy(ctx, &enc);
    if (ctx) exr_finish(&ctx);
    {
        char what[400];
        snprintf(what, sizeof what, "%s: %s", step, exr_message(&log, rv));
        s = write_failed(path, tmp, what, code, err);
    }
    free(tmp);
    return s;
}

static clvr_status read_exr(const char *path, clvr_image *out, clvr_error *err)
{
    exr_log log = {{0}};
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = exr_on_error;
    init.user_data = &log;
    exr_context_t ctx = NULL;
    exr_decode_pipeline_t dec = EXR_DECODE_PIPELINE_INITIALIZER;
    int dec_ready = 0, lines = 1;
    float *planes = NULL;
    clvr_status s = CLVR_OK;
    exr_result_t rv = exr_start_read(&ctx, path, &init);
    if (rv != EXR_ERR_SUCCESS) {
        s = clvr_error_set(err, CLVR_ERR_IO, "cannot read OpenEXR %s: %s", path, exr_message(&log, rv));
        goto cleanup;
    }
    exr_storage_t storage;
    exr_attr_box2i_t dw;
    if (exr_get_storage(ctx, 0, &storage) != EXR_ERR_SUCCESS || storage != EXR_STORAGE_SCANLINE ||
        exr_get_data_window(ctx, 0, &dw) != EXR_ERR_SUCCESS ||
        exr_get_scanlines_per_chunk(ctx, 0, &lines) != EXR_ERR_SUCCESS || lines < 1 || lines > 4096) {
        s = clvr_error_set(err, CLVR_ERR_FORMAT, "%s: only flat scanline OpenEXR images are supported", path);
        goto cleanup;
    }
    int64_t w = (int64_t)dw.max.x - dw.min.x + 1, h = (int64_t)dw.max.y - dw.min.y + 1;
    if (w < 1 || h < 1 || w > CLVR_IMAGE_MAX_DIM || h > CLVR_IMAGE_MAX_DIM) {
        s = clvr_error_set(err, CLVR_ERR_FORMAT, "%s: data window %lldx%lld is empty or too large", path,
                           (long long)w, (long long)h);
        goto cleanup;
    }
    s = clvr_image_alloc(out, (uint32_t)w, (uint32_t)h, err);
    if (s != CLVR_OK) goto cleanup;
    for (size_t i = 0; i < (size_t)w * (size_t)h; ++i) out->rgba[4 * i + 3] = 1.0f; /* no A channel: opaque */
    /* Each channel is decoded into its own plane and interleaved here:
     * OpenEXR 3.1's unpackers take a fast path for interleaved destinations
     * that assumes the file's (alphabetical, A B G R) channel order when
     * converting half to float. */
    planes = malloc(sizeof(float) * 4 * (size_t)lines * (size_t)w);
    if (!planes) { s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "out of memory reading %s", path); goto cleanup; }
    for (int64_t y = dw.min.y; y <= dw.max.y; y += lines) {
        exr_chunk_info_t ci;
        rv = exr_read_scanline_chunk_info(ctx, 0, (int)y, &ci);
        if (rv == EXR_ERR_SUCCESS) rv = dec_ready ? exr_decoding_update(ctx, 0, &ci, &dec)
                                                  : exr_decoding_initialize(ctx, 0, &ci, &dec);
        if (rv != EXR_ERR_SUCCESS) break;
        if (ci.height < 1 || ci.height > lines || ci.start_y < dw.min.y || ci.start_y + ci.height - 1 > dw.max.y) {
            s = clvr_error_set(err, CLVR_ERR_FORMAT, "%s: OpenEXR chunk at row %d is inconsistent", path, ci.start_y);
            goto cleanup;
        }
        int found = 0;
        size_t plane = (size_t)ci.height * (size_t)w;
        for (int c = 0; c < dec.channel_count; ++c) {
            exr_coding_channel_info_t *ch = &dec.channels[c];
            const char *nm = ch->channel_name;
            int k = !strcmp(nm, "R") ? 0 : !strcmp(nm, "G") ? 1 : !strcmp(nm, "B") ? 2 : !strcmp(nm, "A") ? 3 : -1;
            if (k < 0 || ch->x_samples != 1 || ch->y_samples != 1 || (found & (1 << k))) {
                ch->decode_to_ptr = NULL;
                continue;
            }
            found |= 1 << k;
            ch->decode_to_ptr = (uint8_t *)(planes + (size_t)k * plane);
            ch->user_pixel_stride = sizeof(float);
            ch->user_line_stride = (int32_t)(sizeof(float) * (size_t)w);
            ch->user_data_type = EXR_PIXEL_FLOAT;
            ch->user_bytes_per_element = sizeof(float);
        }
        if ((found & 7) != 7) {
            s = clvr_error_set(err, CLVR_ERR_FORMAT, "%s: OpenEXR file has no R, G and B channels", path);
            goto cleanup;
        }
        if (!dec_ready) rv = exr_decoding_choose_default_routines(ctx, 0, &dec);
        dec_ready = 1;
        if (rv == EXR_ERR_SUCCESS) rv = exr_decoding_run(ctx, 0, &dec);
        if (rv != EXR_ERR_SUCCESS) break;
        float *dst = out->rgba + (size_t)(ci.start_y - dw.min.y) * (size_t)w * 4;
        for (int k = 0; k < 4; ++k)
            if (found & (1 << k))
                for (size_t i = 0; i < plane; ++i) dst[4 * i + k] = planes[(size_t)k * plane + i];
    }
    if (rv != EXR_ERR_SUCCESS)
        s = clvr_error_set(err, CLVR_ERR_FORMAT, "cannot read OpenEXR %s: %s", path, exr_message(&log, rv));
cleanup:
    free(planes);
    if (dec_ready) exr_decoding_destroy(ctx, &dec);
    if (ctx) exr_finish(&ctx);
    if (s != CLVR_OK) clvr_image_free(out);
    return s;
}

/* ------------------------------------------------------------ dispatch */

int clvr_image_is_png(const char *path) { return format_of(path) == FMT_PNG; }

clvr_status clvr_image_check_output(const char *path, clvr_error *err)
{
    if (format_of(path) == FMT_NONE)
        return clvr_error_set(err, CLVR_ERR_USAGE, "%s: unknown image extension; supported: .exr, .png, .pfm", path);
    char dir[4096];
    const char *slash = strrchr(path, '/');
    if (!slash) snprintf(dir, sizeof dir, ".");
    else if (slash == path) snprintf(dir, sizeof dir, "/");
    else snprintf(dir, sizeof dir, "%.*s", (int)(slash - path), path);
    if (access(dir, W_OK) != 0)
        return clvr_error_set(err, CLVR_ERR_WRITE, "cannot write %s: directory %s: %s", path, dir, strerror(errno));
    return CLVR_OK;
}

clvr_status clvr_image_write(const char *path, uint32_t width, uint32_t height, const float *rgba, clvr_error *err)
{
    return clvr_image_write_display(path, width, height, rgba, NULL, err);
}

int clvr_image_numbered_path(const char *path, uint32_t index, char *out, size_t size)
{
    const char *slash = strrchr(path, '/');
    const char *dot = strrchr(slash ? slash : path, '.');
    /* A leading dot names a hidden file, not an extension. */
    if (dot && (dot == path || dot[-1] == '/')) dot = NULL;
    size_t stem = dot ? (size_t)(dot - path) : strlen(path);
    int n = snprintf(out, size, "%.*s.%04u%s", (int)stem, path, index, dot ? dot : "");
    return n >= 0 && (size_t)n < size;
}

clvr_status clvr_image_write_display(const char *path, uint32_t width, uint32_t height, const float *rgba,
                                     const clvr_image_display *display, clvr_error *err)
{
    image_format fmt = format_of(path);
    if (fmt == FMT_NONE)
        return clvr_error_set(err, CLVR_ERR_USAGE, "%s: unknown image extension; supported: .exr, .png, .pfm", path);
    if (width == 0 || height == 0 || width > CLVR_IMAGE_MAX_DIM || height > CLVR_IMAGE_MAX_DIM || !rgba)
        return clvr_error_set(err, CLVR_ERR_USAGE, "%s: image size %ux%u: expected 1..%u pixels per side", path,
                              width, height, CLVR_IMAGE_MAX_DIM);
    switch (fmt) {
    case FMT_EXR: return write_exr(path, width, height, rgba, err);
    case FMT_PNG: return write_png(path, width, height, rgba, display, err);
    default: return write_pfm(path, width, height, rgba, err);
    }
}

clvr_status clvr_image_read(const char *path, clvr_image *out, clvr_error *err)
{
    memset(out, 0, sizeof *out);
    switch (format_of(path)) {
    case FMT_EXR: return read_exr(path, out, err);
    case FMT_PNG: return read_png(path, out, err);
    case FMT_PFM: return read_pfm(path, out, err);
    default:
        return clvr_error_set(err, CLVR_ERR_USAGE, "%s: unknown image extension; supported: .exr, .png, .pfm", path);
    }
}
