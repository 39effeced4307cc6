/* replay_main.c: main() for the fuzz_replay_<target> tests, which run in
 * every build (gcc or clang, with or without sanitizers): feeds each file
 * named on the command line, or each file in each directory named, to the
 * target's LLVMFuzzerTestOneInput once, in name order. A contract violation
 * aborts (the test fails and names the file); files whose names start with
 * '.' or "README" are skipped. Fails when it found no input at all, so a
 * wrong path cannot pass silently. */
#include <dirent.h>
#include <errno.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static int replay_file(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f) {
        fprintf(stderr, "replay: cannot open %s: %s\n", path, strerror(errno));
        return 1;
    }
    size_t cap = 1 << 16, n = 0;
    uint8_t *buf = malloc(cap);
    for (;;) {
        if (!buf) { fclose(f); fprintf(stderr, "replay: out of memory for %s\n", path); return 1; }
        n += fread(buf + n, 1, cap - n, f);
        if (n < cap) break;
        uint8_t *grown = realloc(buf, cap * 2);
        if (!grown) free(buf);
        buf = grown;
        cap *= 2;
    }
    int bad = ferror(f);
    fclose(f);
    if (bad) { free(buf); fprintf(stderr, "replay: read error on %s\n", path); return 1; }
    /* An exact-size copy, so a read past the end is a heap overflow. */
    uint8_t *exact = malloc(n ? n : 1);
    if (!exact) { free(buf); return 1; }
    memcpy(exact, buf, n);
    free(buf);
    fprintf(stderr, "replay: %s (%zu bytes)\n", path, n);
    LLVMFuzzerTestOneInput(exact, n);
    free(exact);
    return 0;
}

static int skip_name(const char *name)
{
    return name[0] == '.' || strncmp(name, "README", 6) == 0;
}

int main(int argc, char **argv)
{
    unsigned count = 0, failed = 0;
    for (int i = 1; i < argc; ++i) {
        struct stat st;
        if (stat(argv[i], &st) != 0) {
            fprintf(stderr, "replay: %s: %s\n", argv[i], strerror(errno));
            ++failed;
            continue;
        }
        if (!S_ISDIR(st.st_mode)) {
            failed += (unsigned)replay_file(argv[i]);
            ++count;
            continue;
        }
        struct dirent **list = NULL;
        int n = scandir(argv[i], &list, NULL, alphasort);
        if (n < 0) {
            fprintf(stderr, "replay: cannot list %s: %s\n", argv[i], strerror(errno));
            ++failed;
            continue;
        }
        for (int k = 0; k < n; ++k) {
            char path[4096];
            snprintf(path, sizeof path, "%s/%s", argv[i], list[k]->d_name);
            struct stat fs;
            if (!skip_name(list[k]->d_name) && stat(path, &fs) == 0 && S_ISREG(fs.st_mode)) {
                failed += (unsigned)replay_file(path);
                ++count;
            }
            free(list[k]);
        }
        free(list);
    }
    printf("replay: %u inputs, %u could not be read\n", count, failed);
    if (count == 0) fprintf(stderr, "replay: no inputs found in the paths given\n");
    return count == 0 || failed ? 1 : 0;
}
