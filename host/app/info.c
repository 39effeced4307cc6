#include "info.h"

void clvr_info_print(FILE *out, const char *name, const clvr_mesh *m)
{
    const uint64_t n = clvr_mesh_num_elements(m);
    const uint64_t vb = clvr_mesh_vertex_bytes(m), ib = clvr_mesh_index_bytes(m);
    fprintf(out, "mesh        %s\n", name);
    fprintf(out, "vertices    %llu\n", (unsigned long long)m->num_vertices);
    fprintf(out, "elements    %llu\n", (unsigned long long)n);
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t)
        fprintf(out, "  %-9s %llu\n", clvr_cell_type_name(t), (unsigned long long)m->num_cells[t]);
    if (m->skipped_cells)
        fprintf(out, "left out    %llu cells of other types (surface, line, polyhedron)\n",
                (unsigned long long)m->skipped_cells);
    fprintf(out, "bounds      [%g, %g, %g] - [%g, %g, %g]\n", m->bounds_lo[0], m->bounds_lo[1], m->bounds_lo[2],
            m->bounds_hi[0], m->bounds_hi[1], m->bounds_hi[2]);
    fprintf(out, "scalar      %s, range [%g, %g]\n", m->scalar_name[0] ? m->scalar_name : "(unnamed)", m->scalar_min,
            m->scalar_max);
    fprintf(out, "bytes       vertices+scalars %.3f MB, indices %.3f MB, total %.3f MB (%.1f bytes/element)\n",
            (double)vb / 1e6, (double)ib / 1e6, (double)(vb + ib) / 1e6, n ? (double)(vb + ib) / (double)n : 0.0);
}
