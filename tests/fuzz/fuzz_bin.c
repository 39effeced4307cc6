/* fuzz_bin.c: libFuzzer target for clvr_mesh_parse_bin (see fuzz_mesh.h for
 * what is checked). Built as fuzz_bin with CLVR_FUZZ=ON (clang), and as
 * fuzz_replay_bin in every build, which replays tests/fuzz/regressions/bin
 * and the seeds. */
#include "fuzz_mesh.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    return fuzz_mesh_one(clvr_mesh_parse_bin, data, size, "fuzz.bin");
}
