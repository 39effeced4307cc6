#include "info.h"

clvr_result clvr_info_print(FILE *out, const char *name, const clvr_dataset *ds, clvr_message *msg)
{
    static const char *const type_names[4] = {"tets", "pyramids", "wedges", "hexes"};
    clvr_dataset_info d;
    d.size = sizeof d;
    clvr_result r = clvr_dataset_get_info(ds, &d, msg);
    if (r != CLVR_RESULT_OK) return r;
    const uint64_t n = d.num_elements, vb = d.bytes_points, ib = d.bytes_indices;
    fprintf(out, "mesh        %s\n", name);
    fprintf(out, "vertices    %llu\n", (unsigned long long)d.num_points);
    fprintf(out, "elements    %llu\n", (unsigned long long)n);
    for (uint32_t t = 0; t < 4; ++t) fprintf(out, "  %-9s %llu\n", type_names[t], (unsigned long long)d.num_cells[t]);
    if (d.skipped_cells)
        fprintf(out, "left out    %llu cells of other types (surface, line, polyhedron)\n",
                (unsigned long long)d.skipped_cells);
    fprintf(out, "bounds      [%g, %g, %g] - [%g, %g, %g]\n", d.lo[0], d.lo[1], d.lo[2], d.hi[0], d.hi[1], d.hi[2]);
    const char *how = "";
    if (d.cell_flat)
        how = " (cell data, flat: each element its own value and vertices, --cell-data flat)";
    else if (d.current_is_cell)
        how = " (cell data averaged to the vertices; --cell-data flat shows each element's own value)";
    fprintf(out, "scalar      %s, range [%g, %g]%s\n", d.current_name[0] ? d.current_name : "(unnamed)",
            d.scalar_min, d.scalar_max, how);
    if (d.decomposed_cells)
        fprintf(out, "decomposed  %llu polyhedra into tets and pyramids\n", (unsigned long long)d.decomposed_cells);
    /* Formats with one scalar and no field table list none, as the file has none. */
    const uint32_t listed = d.file_fields;
    if (listed) {
        fprintf(out, "fields      %u (pick with --scalar NAME, point:NAME, cell:NAME, NAME:x|y|z)\n", listed);
        for (uint32_t i = 0; i < listed; ++i) {
            clvr_dataset_field f;
            f.size = sizeof f;
            if ((r = clvr_dataset_get_field(ds, i, &f, msg)) != CLVR_RESULT_OK) return r;
            char range[96];
            if (f.has_range)
                snprintf(range, sizeof range, "%s[%g, %g]", f.components > 1 ? "magnitude " : "", f.min, f.max);
            else
                snprintf(range, sizeof range, "(not read)");
            fprintf(out, "  %-5s %-24s %2u component%s  %s%s\n", f.is_cell ? "cell" : "point", f.name, f.components,
                    f.components == 1 ? " " : "s", range, i == d.current_field ? "  <- rendered" : "");
        }
    }
    fprintf(out, "bytes       vertices+scalars %.3f MB, indices %.3f MB, total %.3f MB (%.1f bytes/element)\n",
            (double)vb / 1e6, (double)ib / 1e6, (double)(vb + ib) / 1e6, n ? (double)(vb + ib) / (double)n : 0.0);
    return CLVR_RESULT_OK;
}
