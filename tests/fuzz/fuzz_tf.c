/* fuzz_tf.c: libFuzzer target for clvr_tf_parse (host/io/tf.h), both file
 * formats (text and ParaView JSON; the first non-blank byte decides). The
 * contract checked:
 *   - failure: an error status in err, a one-line message naming the file
 *     ("fuzz.tf:LINE..."), and the transfer function unchanged;
 *   - success: at least one colour and one opacity point, positions
 *     non-decreasing, values finite and in range, a valid window, density
 *     and table size; the baked table (what the kernels read) is finite and
 *     non-negative, and its extinction majorant bounds every lookup.
 * Built as fuzz_tf with CLVR_FUZZ=ON (clang) and as fuzz_replay_tf in every
 * build (tests/fuzz/regressions/tf and the seeds). */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "tf.h"
#include "fuzz_assert.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static int same_tf(const clvr_tf *a, const clvr_tf *b)
{
    return a->space == b->space && a->num_colors == b->num_colors && a->num_opacity == b->num_opacity &&
           !memcmp(a->colors, b->colors, 4 * sizeof(float) * a->num_colors) &&
           !memcmp(a->opacity, b->opacity, 4 * sizeof(float) * a->num_opacity) && a->range_set == b->range_set &&
           a->density == b->density && a->table_size == b->table_size && !strcmp(a->name, b->name);
}

/* Points are (x, r, g, b) or (x, opacity, midpoint, sharpness): every lane
 * is in [0, 1] (x is normalised to the window, docs/transfer-function.md). */
static void check_points(const float *p, uint32_t n, const char *what)
{
    for (uint32_t i = 0; i < n; ++i) {
        for (int k = 0; k < 4; ++k)
            FUZZ_ASSERT(p[4 * i + k] >= 0.0f && p[4 * i + k] <= 1.0f, "%s[%u] lane %d = %g outside [0, 1]", what, i,
                        k, (double)p[4 * i + k]);
        if (i) FUZZ_ASSERT(p[4 * i] >= p[4 * (i - 1)], "%s positions decrease at %u", what, i);
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    clvr_tf tf = {0}, before = {0};
    clvr_error err = {0};
    FUZZ_ASSERT(clvr_tf_init(&tf, NULL, &err) == CLVR_OK, "%s", err.msg);
    FUZZ_ASSERT(clvr_tf_init(&before, NULL, &err) == CLVR_OK, "%s", err.msg);
    /* A copy without a terminator, so ASan sees any read past len. */
    char *text = malloc(size ? size : 1);
    FUZZ_ASSERT(text != NULL, "out of memory");
    if (size) memcpy(text, data, size);
    clvr_status s = clvr_tf_parse(&tf, text, size, "fuzz.tf", &err);
    free(text);
    if (s != CLVR_OK) {
        FUZZ_ASSERT(err.status == s && s < CLVR_STATUS_COUNT, "status %d / %d", (int)s, (int)err.status);
        FUZZ_ASSERT(strncmp(err.msg, "fuzz.tf", 7) == 0, "message does not start with the file name: %s", err.msg);
        FUZZ_ASSERT(strchr(err.msg, '\n') == NULL, "message is not one line: %s", err.msg);
        FUZZ_ASSERT(same_tf(&tf, &before), "a failed parse changed the transfer function (%s)", err.msg);
    } else {
        FUZZ_ASSERT(tf.num_colors >= 1 && tf.colors, "no colours");
        FUZZ_ASSERT(tf.num_opacity >= 1 && tf.opacity, "no opacity points");
        FUZZ_ASSERT(tf.space < CLVR_TF_SPACE_COUNT, "space %u", tf.space);
        check_points(tf.colors, tf.num_colors, "colors");
        check_points(tf.opacity, tf.num_opacity, "opacity");
        FUZZ_ASSERT(!tf.range_set || (isfinite(tf.range_lo) && isfinite(tf.range_hi) && tf.range_lo < tf.range_hi),
                    "window [%g, %g]", (double)tf.range_lo, (double)tf.range_hi);
        FUZZ_ASSERT(isfinite(tf.density) && tf.density >= 0.0f, "density %g", (double)tf.density);
        uint32_t n = clvr_tf_table_size(&tf);
        FUZZ_ASSERT(n >= 2 && n <= CLVR_TF_MAX_TABLE, "table size %u", n);
        float *table = malloc((size_t)n * 4 * sizeof(float));
        FUZZ_ASSERT(table != NULL, "out of memory");
        clvr_tf_bake(&tf, table, n);
        float wmax = 0.0f;
        for (uint32_t i = 0; i < 4 * n; ++i) {
            FUZZ_ASSERT(isfinite(table[i]) && table[i] >= 0.0f, "table[%u] = %g", i, (double)table[i]);
            if (i % 4 == 3 && table[i] > wmax) wmax = table[i];
        }
        for (uint32_t i = 0; i < 4 * n; i += 4)
            FUZZ_ASSERT(table[i] <= 1.0f && table[i + 1] <= 1.0f && table[i + 2] <= 1.0f, "colour above 1 at %u",
                        i / 4);
        free(table);
    }
    clvr_tf_free(&tf);
    clvr_tf_free(&before);
    return 0;
}
