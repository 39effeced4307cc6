/* fuzz_vtk.c: libFuzzer target for clvr_mesh_parse_vtk (see fuzz_mesh.h for
 * what is checked). Built as fuzz_vtk with CLVR_FUZZ=ON (clang), and as
 * fuzz_replay_vtk in every build, which replays tests/fuzz/regressions/vtk
 * and the seeds. Each input is parsed with the default array and again with
 * a --scalar spec (and --cell-data flat) chosen by its last byte, so that
 * components, cell averaging, flat cells and polyhedra with cell data are
 * fuzzed too. */
#include "fuzz_mesh.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static clvr_status parse_with_spec(const void *data, size_t size, const char *name, const clvr_load_options *opt,
                                   clvr_mesh *out, clvr_error *err)
{
    static const char *const specs[] = {"cell:c", "c", "vel:y", "uvw", "point:s", "id", "s:x"};
    clvr_load_options o = *opt;
    const uint8_t last = size ? ((const uint8_t *)data)[size - 1] : 0;
    o.scalar_name = specs[last % (sizeof specs / sizeof specs[0])];
    o.cell_flat = (last >> 7) & 1;
    return clvr_mesh_parse_vtk(data, size, name, &o, out, err);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fuzz_mesh_one(clvr_mesh_parse_vtk, data, size, "fuzz.vtk");
    return fuzz_mesh_one(parse_with_spec, data, size, "fuzz.vtk");
}
