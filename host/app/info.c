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
    const char *how = "";
    if (m->cell_flat)
        how = " (cell data, flat: each element its own value and vertices, --cell-data flat)";
    else if (m->num_fields && m->fields[m->scalar_field].association == CLVR_FIELD_CELL)
        how = " (cell data averaged to the vertices; --cell-data flat shows each element's own value)";
    fprintf(out, "scalar      %s, range [%g, %g]%s\n", m->scalar_name[0] ? m->scalar_name : "(unnamed)", m->scalar_min,
            m->scalar_max, how);
    if (m->decomposed_cells)
        fprintf(out, "decomposed  %llu polyhedra into tets and pyramids\n", (unsigned long long)m->decomposed_cells);
    if (m->num_fields) {
        fprintf(out, "fields      %u (pick with --scalar NAME, point:NAME, cell:NAME, NAME:x|y|z)\n", m->num_fields);
        for (uint32_t i = 0; i < m->num_fields; ++i) {
            const clvr_field_info *f = &m->fields[i];
            char range[96];
            if (f->has_range)
                snprintf(range, sizeof range, "%s[%g, %g]", f->components > 1 ? "magnitude " : "", f->min, f->max);
            else
                snprintf(range, sizeof range, "(not read)");
            fprintf(out, "  %-5s %-24s %2u component%s  %s%s\n", f->association ? "cell" : "point", f->name,
                    f->components, f->components == 1 ? " " : "s", range, i == m->scalar_field ? "  <- rendered" : "");
        }
    }
    fprintf(out, "bytes       vertices+scalars %.3f MB, indices %.3f MB, total %.3f MB (%.1f bytes/element)\n",
            (double)vb / 1e6, (double)ib / 1e6, (double)(vb + ib) / 1e6, n ? (double)(vb + ib) / (double)n : 0.0);
}
