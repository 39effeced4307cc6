#include "stats.h"

#include <errno.h>
#include <string.h>
#include <unistd.h>

#include <stdio.h>

void clvr_stats_from_dataset(clvr_stats *s, const clvr_dataset_info *d)
{
    s->elements = d->num_elements;
    s->vertices = d->num_points;
    for (uint32_t t = 0; t < 4; ++t) s->cells[t] = d->num_cells[t];
    s->bytes_vertices = d->bytes_points;
    s->bytes_indices_before = d->bytes_indices;
}

void clvr_stats_from_render(clvr_stats *s, const clvr_render_stats *rc)
{
    snprintf(s->method, sizeof s->method, "%s", rc->method);
    snprintf(s->estimator, sizeof s->estimator, "%s", rc->estimator);
    s->macrocells = rc->macrocells;
    s->width = rc->width;
    s->height = rc->height;
    s->frames = rc->frames;
    s->rays = rc->rays;
    s->samples = rc->samples;
    s->null_collisions = rc->null_collisions;
    s->frame_s = rc->frames ? rc->kernel_s / (double)rc->frames : 0.0;
    s->rays_per_s = rc->kernel_s > 0 ? (double)rc->rays / rc->kernel_s : 0.0;
    s->samples_per_ray = rc->rays ? (double)rc->samples / (double)rc->rays : 0.0;
    s->null_collisions_per_ray = rc->rays ? (double)rc->null_collisions / (double)rc->rays : 0.0;
}

void clvr_stats_from_scene(clvr_stats *s, const clvr_scene_stats *c)
{
    s->have_clusters = 1;
    s->bytes_vertices_after = c->bytes_points_after;
    s->bytes_indices_after = c->bytes_indices_after;
    if (c->bytes_indices_before) s->bytes_indices_before = c->bytes_indices_before;
    s->bytes_bvh = c->bytes_bvh;
    s->bytes_element_boxes = c->bytes_element_boxes;
    s->bytes_entry_grids = c->bytes_entry_grids;
    s->bytes_bvh_one_per_leaf = c->bytes_bvh_one_per_leaf;
    s->bytes_sampling = c->bytes_sampling;
    s->num_instances = c->instances;
    s->num_instances16 = c->instances16;
    for (int t = 0; t < 4; ++t) s->collapsed[t] = c->collapsed_cells[t];
    s->num_leaves = c->leaves;
    s->num_sampling = c->sampling_clusters;
    s->leaf_size = c->leaf_size;
    s->sampling_size = c->sampling_size;
    s->num_stages = 0;
    for (uint32_t i = 0; i < c->num_stages && s->num_stages < CLVR_STATS_MAX_STAGES; ++i) {
        snprintf(s->stage_name[s->num_stages], sizeof s->stage_name[0], "%s", c->stage_name[i]);
        s->stage_s[s->num_stages++] = c->stage_s[i];
    }
}

static double per_element(uint64_t bytes, uint64_t elements)
{
    return elements ? (double)bytes / (double)elements : 0.0;
}

void clvr_stats_print(FILE *out, const clvr_stats *s)
{
    if (s->have_mesh) {
        fprintf(out, "mesh: %llu elements (%llu tets, %llu pyramids, %llu wedges, %llu hexes), %llu vertices, "
                     "loaded in %.3f s\n",
                (unsigned long long)s->elements, (unsigned long long)s->cells[0], (unsigned long long)s->cells[1],
                (unsigned long long)s->cells[2], (unsigned long long)s->cells[3], (unsigned long long)s->vertices,
                s->load_s);
    }
    if (s->have_clusters) {
        fprintf(out, "\n| memory (paper Table 1) | before | after | bytes/element before | after |\n");
        fprintf(out, "|---|---:|---:|---:|---:|\n");
        fprintf(out, "| vertices | %.3f MB | %.3f MB | %.2f | %.2f |\n", s->bytes_vertices / 1e6,
                s->bytes_vertices_after / 1e6, per_element(s->bytes_vertices, s->elements),
                per_element(s->bytes_vertices_after, s->elements));
        fprintf(out, "| indices | %.3f MB | %.3f MB | %.2f | %.2f |\n", s->bytes_indices_before / 1e6,
                s->bytes_indices_after / 1e6, per_element(s->bytes_indices_before, s->elements),
                per_element(s->bytes_indices_after, s->elements));
        fprintf(out, "| BVH (1 / %u elements per leaf) | %.3f MB | %.3f MB | %.2f | %.2f |\n", s->leaf_size,
                s->bytes_bvh_one_per_leaf / 1e6, s->bytes_bvh / 1e6,
                per_element(s->bytes_bvh_one_per_leaf, s->elements), per_element(s->bytes_bvh, s->elements));
        fprintf(out, "| element boxes (not in the paper) | | %.3f MB | | %.2f |\n", s->bytes_element_boxes / 1e6,
                per_element(s->bytes_element_boxes, s->elements));
        fprintf(out, "| entry and occupancy grids (not in the paper) | | %.3f MB | | %.2f |\n", s->bytes_entry_grids / 1e6,
                per_element(s->bytes_entry_grids, s->elements));
        fprintf(out, "| sampling clusters | | %.3f MB | | %.2f |\n", s->bytes_sampling / 1e6,
                per_element(s->bytes_sampling, s->elements));
        fprintf(out, "| boundary faces rays are cut to (%llu; 0: none kept) | | %.3f MB | | %.2f |\n",
                (unsigned long long)s->hull_faces, s->bytes_hull / 1e6, per_element(s->bytes_hull, s->elements));
        fprintf(out, "\nclusters: %llu instances (%llu with 16-bit indices), %llu leaves of %u, %llu sampling "
                     "clusters of %u\n",
                (unsigned long long)s->num_instances, (unsigned long long)s->num_instances16,
                (unsigned long long)s->num_leaves, s->leaf_size, (unsigned long long)s->num_sampling,
                s->sampling_size);
        int types = 0;
        for (int t = 0; t < 4; ++t) types += s->cells[t] > 0;
        if (s->collapsed[0] + s->collapsed[1] + s->collapsed[2] > 0)
            fprintf(out, "cell types on one curve: %llu tets, %llu pyramids and %llu wedges stored as hexes with "
                         "repeated corners (--one-curve)\n",
                    (unsigned long long)s->collapsed[0], (unsigned long long)s->collapsed[1],
                    (unsigned long long)s->collapsed[2]);
        else if (types > 1)
            fprintf(out, "cell types: one curve per type (--one-curve)\n");
        fprintf(out, "\n| preprocessing stage | seconds | elements/s |\n|---|---:|---:|\n");
        for (int i = 0; i < s->num_stages; ++i)
            fprintf(out, "| %s | %.4f | %.3g |\n", s->stage_name[i], s->stage_s[i],
                    s->stage_s[i] > 0 ? (double)s->elements / s->stage_s[i] : 0.0);
        fprintf(out, "| total (wall) | %.4f | %.3g |\n", s->preprocess_s,
                s->preprocess_s > 0 ? (double)s->elements / s->preprocess_s : 0.0);
        fprintf(out, "\nkernel compilation (not in the total): %.3f s\n", s->kernel_build_s);
        if (s->partitions) fprintf(out, "partitions: %u\n", s->partitions);
    }
    if (s->bytes_peak_rss || s->bytes_resident) {
        fprintf(out, "memory: peak resident %.3f GB, resident after preprocessing %.3f GB (ratio %.2f)\n",
                s->bytes_peak_rss / 1e9, s->bytes_resident / 1e9,
                s->bytes_resident ? (double)s->bytes_peak_rss / (double)s->bytes_resident : 0.0);
    }
    if (s->have_render) {
        char grid[32] = "";
        if (s->macrocells) snprintf(grid, sizeof grid, " (%u^3 macrocells)", s->macrocells);
        fprintf(out, "\nrender: %s%s, %s, %ux%u, %llu frames, %.4f s/frame (device), %.3f Mrays/s, %.2f samples/ray, "
                     "%.2f null collisions/ray\n",
                s->method, grid, s->estimator, s->width, s->height, (unsigned long long)s->frames,
                s->frame_s, s->rays_per_s / 1e6, s->samples_per_ray, s->null_collisions_per_ray);
        /* The two device passes that s/frame does not show by itself: the
         * light grid is inside its sum (once per transfer function), the
         * image pass is not (once per image read). */
        fprintf(out, "light grid %.4f s (device, in the frames' sum), image pass %.4f s (device, once per image, "
                     "not in s/frame)\n",
                s->light_s, s->image_s);
        if (s->adaptive > 0.0 && s->width && s->height)
            fprintf(out, "adaptive sampling (threshold %g): %.0f pixels (%.1f%%) got one more sample per frame (in "
                         "s/frame), chosen in %.4f s (host, once)\n",
                    s->adaptive, s->refine_pixels, 100.0 * s->refine_pixels / ((double)s->width * s->height),
                    s->select_s);
        if (s->pilot_walk_cells >= 0.0)
            fprintf(out, "auto's pilot: %s, from two samples of each way in %.0f pixels, %.4f s (host, once, not in "
                         "s/frame)\n",
                    s->pilot_walk_cells > 0.0 ? "the walk through every cell" : "urm at the cells other than tets",
                    s->pilot_pixels, s->pilot_s);
        if (s->bytes_adjacency)
            fprintf(out, "face adjacency of the walk estimator (built at its first frame): %.3f MB, %.2f bytes/element\n",
                    s->bytes_adjacency / 1e6, per_element(s->bytes_adjacency, s->elements));
    }
}

/* Writes one "key": number pair; values that are not finite become null. */
static void jnum(FILE *f, const char *indent, const char *key, double v, int comma)
{
    if (v == v && v - v == 0.0)
        fprintf(f, "%s\"%s\": %.17g%s\n", indent, key, v, comma ? "," : "");
    else
        fprintf(f, "%s\"%s\": null%s\n", indent, key, comma ? "," : "");
}

/* A failed write: msg names the file and the OS error (clvr's ERR_WRITE). */
static clvr_result write_failed(clvr_message *msg, const char *path, int e)
{
    msg->result = CLVR_RESULT_ERR_WRITE;
    snprintf(msg->text, sizeof msg->text, "cannot write %s: %s", path, strerror(e));
    return msg->result;
}

clvr_result clvr_stats_write_json(const char *path, const clvr_stats *s, clvr_message *msg)
{
    char tmp[4096];
    snprintf(tmp, sizeof tmp, "%s.tmp.%ld", path, (long)getpid());
    FILE *f = fopen(tmp, "w");
    if (!f) return write_failed(msg, path, errno);
    struct { const char *k; double v; } b[] = {
        {"vertices", (double)s->bytes_vertices},
        {"vertices_after", (double)s->bytes_vertices_after},
        {"indices_before", (double)s->bytes_indices_before},
        {"indices_after", (double)s->bytes_indices_after},
        {"bvh", (double)s->bytes_bvh},
        {"bvh_one_per_leaf", (double)s->bytes_bvh_one_per_leaf},
        {"sampling", (double)s->bytes_sampling},
        {"element_boxes", (double)s->bytes_element_boxes},
        {"entry_grids", (double)s->bytes_entry_grids},
        {"hull", (double)s->bytes_hull},
        {"adjacency", (double)s->bytes_adjacency},
        {"peak_rss", (double)s->bytes_peak_rss},
        {"resident", (double)s->bytes_resident},
    };
    struct { const char *k; double v; } r[] = {
        {"rays_per_s", s->rays_per_s},
        {"samples_per_ray", s->samples_per_ray},
        {"null_collisions_per_ray", s->null_collisions_per_ray},
        {"frame_s", s->frame_s},
        {"macrocells", (double)s->macrocells},
        {"frames", (double)s->frames},
        {"rays", (double)s->rays},
        {"width", (double)s->width},
        {"height", (double)s->height},
        {"wall_s", s->render_wall_s},
        {"light_s", s->light_s},
        {"image_s", s->image_s},
        {"adaptive", s->adaptive},
        {"refine_pixels", s->refine_pixels},
        {"select_s", s->select_s},
        {"pilot_s", s->pilot_s},
        {"pilot_pixels", s->pilot_pixels},
        {"pilot_walk_cells", s->pilot_walk_cells},
    };
    const size_t nb = sizeof b / sizeof b[0], nr = sizeof r / sizeof r[0];
    fprintf(f, "{\n");
    jnum(f, "  ", "elements", (double)s->elements, 1);
    jnum(f, "  ", "vertices", (double)s->vertices, 1);
    fprintf(f, "  \"cells\": {\"tets\": %llu, \"pyramids\": %llu, \"wedges\": %llu, \"hexes\": %llu},\n",
            (unsigned long long)s->cells[0], (unsigned long long)s->cells[1], (unsigned long long)s->cells[2],
            (unsigned long long)s->cells[3]);
    fprintf(f, "  \"bytes\": {\n");
    for (size_t i = 0; i < nb; ++i) jnum(f, "    ", b[i].k, b[i].v, i + 1 < nb);
    fprintf(f, "  },\n");
    fprintf(f, "  \"clusters\": {\"instances\": %llu, \"instances16\": %llu, \"leaves\": %llu, \"leaf_size\": %u, "
               "\"sampling\": %llu, \"sampling_size\": %u, \"collapsed\": {\"tets\": %llu, \"pyramids\": %llu, "
               "\"wedges\": %llu}},\n",
            (unsigned long long)s->num_instances, (unsigned long long)s->num_instances16,
            (unsigned long long)s->num_leaves, s->leaf_size, (unsigned long long)s->num_sampling, s->sampling_size,
            (unsigned long long)s->collapsed[0], (unsigned long long)s->collapsed[1],
            (unsigned long long)s->collapsed[2]);
    fprintf(f, "  \"time\": {\n");
    jnum(f, "    ", "load_s", s->load_s, 1);
    for (int i = 0; i < s->num_stages; ++i) {
        char key[96];
        snprintf(key, sizeof key, "%s_s", s->stage_name[i]);
        jnum(f, "    ", key, s->stage_s[i], 1);
    }
    jnum(f, "    ", "kernel_build_s", s->kernel_build_s, 1);
    jnum(f, "    ", "preprocess_s", s->preprocess_s, 0);
    fprintf(f, "  },\n");
    if (s->have_render) {
        fprintf(f, "  \"render\": {\n    \"method\": \"%s\",\n    \"estimator\": \"%s\",\n", s->method, s->estimator);
        for (size_t i = 0; i < nr; ++i) jnum(f, "    ", r[i].k, r[i].v, i + 1 < nr);
        fprintf(f, "  },\n");
    }
    /* Flat mirrors of the nested keys. */
    for (size_t i = 0; i < nb; ++i) {
        char key[96];
        snprintf(key, sizeof key, "bytes.%s", b[i].k);
        jnum(f, "  ", key, b[i].v, 1);
    }
    if (s->have_render)
        for (size_t i = 0; i < nr; ++i) {
            char key[96];
            snprintf(key, sizeof key, "render.%s", r[i].k);
            jnum(f, "  ", key, r[i].v, 1);
        }
    jnum(f, "  ", "partitions", (double)s->partitions, 1);
    jnum(f, "  ", "time.kernel_build_s", s->kernel_build_s, 1);
    jnum(f, "  ", "time.preprocess_s", s->preprocess_s, 0);
    fprintf(f, "}\n");
    int bad = ferror(f);
    if (fclose(f) != 0 || bad) {
        const int e = errno;
        remove(tmp);
        return write_failed(msg, path, e);
    }
    if (rename(tmp, path) != 0) {
        int e = errno;
        remove(tmp);
        return write_failed(msg, path, e);
    }
    msg->result = CLVR_RESULT_OK;
    msg->text[0] = '\0';
    return CLVR_RESULT_OK;
}
