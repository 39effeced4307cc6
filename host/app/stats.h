/* stats.h: the figures behind `--stats` and `--stats-json`: memory in the
 * shape of the paper's Table 1 (vertices, indices and BVH before and after
 * compression), preprocessing times per stage, and render throughput. */
#ifndef CLVR_STATS_H
#define CLVR_STATS_H

#include <stdint.h>
#include <stdio.h>

#include "clvr.h"

typedef struct clvr_stats {
    int have_mesh, have_clusters, have_render;
    /* mesh */
    uint64_t elements, vertices;
    uint64_t cells[4];
    double load_s;
    /* memory, bytes */
    uint64_t bytes_vertices;        /* input: float3 position + float scalar per vertex */
    uint64_t bytes_vertices_after;  /* clustered: float4 per (duplicated) vertex */
    uint64_t bytes_indices_before;  /* 32-bit indices */
    uint64_t bytes_indices_after;   /* 16/32-bit per instance cluster */
    uint64_t bytes_bvh;             /* two-level BVH at the chosen leaf size */
    uint64_t bytes_bvh_one_per_leaf;/* estimate for one element per leaf (Table 1 "pre") */
    uint64_t bytes_sampling;        /* sampling clusters */
    uint64_t bytes_element_boxes;   /* quantized element boxes of point location (kernels/locate.h) */
    uint64_t bytes_entry_grids;     /* point location's entry grids (kernels/locate.h) */
    uint64_t bytes_hull;            /* boundary faces and their tree that camera rays are cut to (0: none kept) */
    uint64_t hull_faces;
    uint64_t bytes_adjacency;       /* the walk's face adjacency, built at its first frame (0: not built) */
    double hull_empty_fraction;     /* share of a ray's box chord outside the mesh (the hull's probe) */
    uint64_t bytes_peak_rss;        /* the process's peak resident set (VmHWM) when the stats are written */
    uint64_t bytes_resident;        /* its resident set once the mesh is freed and the renderer is ready:
                                       the footprint the run keeps (CPU devices: device memory included) */
    uint32_t partitions;            /* preprocessing partitions (partition.h) */
    /* clusters */
    uint64_t num_instances, num_instances16, num_leaves, num_sampling;
    uint64_t collapsed[4];          /* tets, pyramids, wedges stored as hexes on one curve (all 0: one curve
                                       per type, or a mesh of one type) */
    uint32_t leaf_size, sampling_size;
    /* times, seconds */
    double preprocess_s;            /* wall time: upload + clustering + BVH, kernel compilation excluded */
    double kernel_build_s;          /* wall time in the driver's compiler (all programs; ms when cached) */
    int num_stages;
    char stage_name[CLVR_STATS_MAX_STAGES][16];
    double stage_s[CLVR_STATS_MAX_STAGES];
    /* render */
    char method[16];
    char estimator[16]; /* what the frames rendered with (auto resolved) */
    uint32_t macrocells; /* dda: cells per axis of the macrocell grid in use (the automatic choice); else 0 */
    uint32_t width, height;
    uint64_t frames, rays, samples, null_collisions;
    double frame_s, rays_per_s, samples_per_ray, null_collisions_per_ray, render_wall_s;
    double light_s; /* device seconds of the light grid's last build (part of frame_s's sum) */
    double image_s; /* device seconds of the image pass that made the image written (not in frame_s) */
    double adaptive;      /* adaptive sampling's threshold (0: off) */
    double refine_pixels; /* pixels that get one more sample per frame (in frame_s; the frames count them once) */
    double select_s;      /* host seconds of choosing them (once) */
    double pilot_s;       /* auto's pilot: host seconds (kernels included; not in frame_s), 0 without one */
    double pilot_pixels;  /* its pixels */
    double pilot_walk_cells; /* 1: it picked the walk through every cell, 0: urm at other cells, -1: no pilot */
} clvr_stats;

/* The figures of the input, of the preprocessing and of the frames, from
 * libclvr's public statistics. */
void clvr_stats_from_dataset(clvr_stats *s, const clvr_dataset_info *d);
void clvr_stats_from_scene(clvr_stats *s, const clvr_scene_stats *c);
void clvr_stats_from_render(clvr_stats *s, const clvr_render_stats *r);

/* Human-readable tables on out. */
void clvr_stats_print(FILE *out, const clvr_stats *s);
/* JSON, written to a temporary file and renamed. Nested objects ("bytes":
 * {"vertices": ...}) and, for tools that look keys up flat, the same values
 * under dotted top-level keys ("bytes.vertices"). */
clvr_result clvr_stats_write_json(const char *path, const clvr_stats *s, clvr_message *msg);

#endif
