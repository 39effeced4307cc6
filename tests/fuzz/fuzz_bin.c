/* fuzz_bin.c: libFuzzer target for clvr_mesh_parse_bin (see fuzz_mesh.h for
 * what is checked). Built as fuzz_bin with CLVR_FUZZ=ON (clang), and as
 * fuzz_replay_bin in every build, which replays tests/fuzz/regressions/bin
 * and the seeds. Each input is parsed with the default field and again with
 * a --scalar spec chosen by its last byte, so that version 2's cell-data
 * averaging, --cell-data flat and component paths see fuzzed tables too. */
#include "fuzz_mesh.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static clvr_status parse_with_spec(const void *data, size_t size, const char *name, const clvr_load_options *opt,
                                   clvr_mesh *out, clvr_error *err)
{
    static const char *const specs[] = {"cell:s", "vel:y", "stress", "s:x", "point:s", "stress:5", "c"};
    clvr_load_options o = *opt;
    const uint8_t last = size ? ((const uint8_t *)data)[size - 1] : 0;
    o.scalar_name = specs[last % (sizeof specs / sizeof specs[0])];
    o.cell_flat = (last >> 7) & 1; /* --cell-data flat */
    return clvr_mesh_parse_bin(data, size, name, &o, out, err);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fuzz_mesh_one(clvr_mesh_parse_bin, data, size, "fuzz.bin");
    return fuzz_mesh_one(parse_with_spec, data, size, "fuzz.bin");
}
