/* series_file.c: see series_file.h. */
#include "series_file.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "json.h"

int clvr_series_is(const char *path)
{
    size_t n = path ? strlen(path) : 0;
    return n > 7 && strcasecmp(path + n - 7, ".series") == 0;
}

void clvr_series_free(char **paths, double *times, uint32_t n)
{
    for (uint32_t i = 0; paths && i < n; ++i) free(paths[i]);
    free(paths);
    free(times);
}

/* The whole file, NUL-terminated; series files are small (1 MiB at most). */
static clvr_status read_text(const char *path, char **out, size_t *len, clvr_error *err)
{
    *out = NULL;
    FILE *f = fopen(path, "rb");
    if (!f) return clvr_error_set(err, CLVR_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
    char *buf = malloc((1u << 20) + 1);
    size_t n = buf ? fread(buf, 1, 1u << 20, f) : 0;
    int more = buf && fgetc(f) != EOF, bad = ferror(f);
    fclose(f);
    if (!buf) return clvr_error_set(err, CLVR_ERR_NO_MEMORY, "%s: out of memory", path);
    if (bad || more) {
        free(buf);
        return clvr_error_set(err, bad ? CLVR_ERR_IO : CLVR_ERR_FORMAT, "%s: %s", path,
                              bad ? "read error" : "longer than 1 MiB; not a series file");
    }
    buf[n] = 0;
    *out = buf;
    *len = n;
    return CLVR_OK;
}

clvr_status clvr_series_read(const char *path, char ***paths_out, double **times_out, uint32_t *n_out, clvr_error *err)
{
    char *text = NULL, **paths = NULL;
    double *times = NULL;
    size_t len = 0;
    uint32_t n = 0;
    clvr_json j = {0};
    *paths_out = NULL;
    *times_out = NULL;
    *n_out = 0;
    clvr_status s = read_text(path, &text, &len, err);
    if (s == CLVR_OK) s = clvr_json_parse(text, len, path, &j, err);
    if (s != CLVR_OK) goto done;
    const clvr_json_node *root = &j.nodes[j.root], *files = NULL;
    if (root->type == CLVR_JSON_OBJECT)
        for (long c = root->child; c >= 0; c = j.nodes[c].next)
            if (clvr_json_key_is(&j, &j.nodes[c], "files")) files = &j.nodes[c];
    if (!files || files->type != CLVR_JSON_ARRAY || files->count == 0) {
        s = clvr_error_set(err, CLVR_ERR_BAD_FIELD,
                           "%s: not a series file: expected {\"files\": [{\"name\": \"step.bin\", \"time\": 0}, ...]} "
                           "(clvr-convert writes one for .pvd, .series and Exodus time steps)", path);
        goto done;
    }
    const char *slash = strrchr(path, '/');
    size_t dirlen = slash ? (size_t)(slash - path) + 1 : 0;
    paths = calloc(files->count, sizeof *paths);
    times = calloc(files->count, sizeof *times);
    if (!paths || !times) {
        s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "%s: out of memory", path);
        goto done;
    }
    for (long c = files->child; c >= 0; c = j.nodes[c].next, ++n) {
        const clvr_json_node *e = &j.nodes[c], *name = NULL;
        times[n] = n;
        if (e->type == CLVR_JSON_OBJECT)
            for (long k = e->child; k >= 0; k = j.nodes[k].next) {
                if (clvr_json_key_is(&j, &j.nodes[k], "name")) name = &j.nodes[k];
                if (clvr_json_key_is(&j, &j.nodes[k], "time") && j.nodes[k].type == CLVR_JSON_NUMBER)
                    times[n] = j.nodes[k].num;
            }
        if (!name || name->type != CLVR_JSON_STRING || name->slen == 0 || memchr(j.arena + name->str, 0, name->slen)) {
            s = clvr_json_fail(&j, err, e->line, e->col, "files[%u] needs a \"name\" string", n);
            goto done;
        }
        const char *nm = j.arena + name->str;
        size_t pre = nm[0] == '/' ? 0 : dirlen;
        paths[n] = malloc(pre + name->slen + 1);
        if (!paths[n]) {
            s = clvr_error_set(err, CLVR_ERR_NO_MEMORY, "%s: out of memory", path);
            goto done;
        }
        memcpy(paths[n], path, pre);
        memcpy(paths[n] + pre, nm, name->slen + 1);
    }
    *paths_out = paths;
    *times_out = times;
    *n_out = n;
    paths = NULL;
    times = NULL;
done:
    clvr_series_free(paths, times, n);
    clvr_json_free(&j);
    free(text);
    return s;
}
