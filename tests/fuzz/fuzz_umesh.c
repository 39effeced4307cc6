/* fuzz_umesh.c: libFuzzer target for clvr_mesh_parse_umesh (see fuzz_mesh.h for
 * what is checked). Built as fuzz_umesh with CLVR_FUZZ=ON (clang), and as
 * fuzz_replay_umesh in every build, which replays tests/fuzz/regressions/umesh
 * and the seeds. */
#include "fuzz_mesh.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    return fuzz_mesh_one(clvr_mesh_parse_umesh, data, size, "fuzz.umesh");
}
