/* tf_auto.c: the automatic transfer function; see tf_auto.h. */
#include "tf_auto.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "scene.h"

void clvr_tf_auto_histogram_kept(const clvr_mesh *m, const uint8_t *keep, float lo, float hi, double *hist,
                                  uint32_t bins)
{
    memset(hist, 0, (size_t)bins * sizeof *hist);
    if (!(hi > lo) || bins == 0) return;
    const double scale = (double)bins / ((double)hi - (double)lo);
    uint64_t e = 0; /* element number across the types, for keep */
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) {
        const uint32_t nv = clvr_cell_vertex_count(t);
        for (uint64_t c = 0; c < m->num_cells[t]; ++c, ++e) {
            if (keep && !keep[e]) continue;
            const uint32_t *idx = m->indices[t] + c * nv;
            if ((c & 0xfffff) == 0xfffff) clvr_mesh_release_all_pages(m); /* a mapped .bin: pages back behind */
            double share = fabs(clvr_scene_cell_volume(t, m->positions, idx)) / nv;
            if (!(share > 0.0) || !isfinite(share)) continue;
            for (uint32_t k = 0; k < nv; ++k) {
                float s = m->scalars[idx[k]];
                if (isnan(s)) continue;
                double p = ((double)s - lo) * scale;
                uint32_t b = p <= 0.0 ? 0u : p >= (double)bins ? bins - 1u : (uint32_t)p;
                hist[b] += share;
            }
        }
    }
}

void clvr_tf_auto_histogram(const clvr_mesh *m, float lo, float hi, double *hist, uint32_t bins)
{
    clvr_tf_auto_histogram_kept(m, NULL, lo, hi, hist, bins);
}

clvr_status clvr_tf_auto_opacity(clvr_tf *tf, const double *hist, uint32_t bins, clvr_error *err)
{
    double total = 0.0;
    uint32_t filled = 0;
    for (uint32_t b = 0; b < bins; ++b) {
        total += hist[b];
        filled += hist[b] > 0.0;
    }
    /* Empty, or one value everywhere (a constant field): nothing is rarer
     * than anything else; keep the curve tf has, so the field still shows. */
    if (!(total > 0.0) || filled < 2) return CLVR_OK;
    const uint32_t n = bins + 2;
    float *pts = malloc((size_t)n * 4 * sizeof(float));
    double *share = malloc((size_t)bins * sizeof *share);
    if (!pts || !share) {
        free(pts);
        free(share);
        return clvr_error_set(err, CLVR_ERR_NO_MEMORY, "out of memory for the automatic opacity");
    }
    /* Shares of the volume, [1 2 1] / 4 smoothed (ends reflected); the mode. */
    uint32_t mode = 0;
    for (uint32_t b = 0; b < bins; ++b) {
        double l = hist[b > 0 ? b - 1 : b], r = hist[b + 1 < bins ? b + 1 : b];
        share[b] = (l + 2.0 * hist[b] + r) / (4.0 * total);
        if (share[b] > share[mode]) mode = b;
    }
    /* Volume on each side of the mode. */
    double below = 0.0, above = 0.0;
    for (uint32_t b = 0; b < mode; ++b) below += hist[b] / total;
    for (uint32_t b = mode + 1; b < bins; ++b) above += hist[b] / total;
    const double lk = log((double)CLVR_TF_AUTO_SHARE);
    double beyond = above; /* volume above bin b (walking up), or below it (walking down) */
    for (uint32_t b = 0; b < bins; ++b) {
        /* Rarity: 0 at SHARE x the uniform share or more, 1 at 1 / SHARE or less. */
        double u = share[b] * bins;
        double a = u > 0.0 ? 0.5 - log(u) / (2.0 * lk) : 1.0;
        a = a < 0.0 ? 0.0 : a > 1.0 ? 1.0 : a;
        /* Side distribution: the fraction of the mode's side of the histogram
         * that lies between the mode and this bin (its middle). */
        double c = 0.0;
        if (b < mode) {
            double sofar = 0.0; /* volume below b */
            for (uint32_t k = 0; k < b; ++k) sofar += hist[k] / total;
            c = below > 0.0 ? 1.0 - (sofar + 0.5 * hist[b] / total) / below : 1.0;
        } else if (b > mode) {
            beyond -= hist[b] / total;
            c = above > 0.0 ? 1.0 - (beyond + 0.5 * hist[b] / total) / above : 1.0;
        }
        c = c < 0.0 ? 0.0 : c > 1.0 ? 1.0 : c;
        a *= pow(c, (double)CLVR_TF_AUTO_GAMMA);
        float *p = pts + 4 * (b + 1);
        p[0] = ((float)b + 0.5f) / (float)bins;
        p[1] = (float)a;
        p[2] = 0.5f;
        p[3] = 0.0f;
    }
    free(share);
    memcpy(pts, pts + 4, 4 * sizeof(float));
    pts[0] = 0.0f;
    memcpy(pts + 4 * (n - 1), pts + 4 * (n - 2), 4 * sizeof(float));
    pts[4 * (n - 1)] = 1.0f;
    free(tf->opacity);
    tf->opacity = pts;
    tf->num_opacity = n;
    return CLVR_OK;
}

#define PROBE_CELLS 48
#define PROBE_RAYS 48

static int cmp_float(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

clvr_status clvr_tf_auto_grid_create(const float bounds_lo[3], const float bounds_hi[3], clvr_tf_auto_grid *g,
                                     clvr_error *err)
{
    memset(g, 0, sizeof *g);
    double h = 0.0;
    for (int a = 0; a < 3; ++a) {
        g->lo[a] = bounds_lo[a];
        g->ext[a] = (double)bounds_hi[a] - g->lo[a];
        if (g->ext[a] > h) h = g->ext[a];
    }
    if (!(h > 0.0) || !isfinite(h)) return CLVR_OK; /* no cells: the median stays 0 */
    h /= PROBE_CELLS;
    for (int a = 0; a < 3; ++a) {
        g->n[a] = (int)ceil(g->ext[a] / h);
        if (g->n[a] < 1) g->n[a] = 1;
        if (g->n[a] > PROBE_CELLS) g->n[a] = PROBE_CELLS;
        if (g->ext[a] < h) { g->lo[a] -= 0.5 * (h - g->ext[a]); g->ext[a] = h; } /* a flat box gets one cell of thickness h */
        g->cell_h[a] = g->ext[a] / g->n[a];
    }
    g->cells = (size_t)g->n[0] * g->n[1] * g->n[2];
    g->sigma = calloc(2 * g->cells, sizeof *g->sigma);
    if (!g->sigma) {
        g->cells = 0;
        return clvr_error_set(err, CLVR_ERR_NO_MEMORY, "out of memory for the automatic density");
    }
    g->covered = g->sigma + g->cells;
    return CLVR_OK;
}

void clvr_tf_auto_grid_free(clvr_tf_auto_grid *g)
{
    free(g->sigma);
    memset(g, 0, sizeof *g);
}

clvr_status clvr_tf_auto_grid_add(clvr_tf_auto_grid *g, const clvr_mesh *m, const uint8_t *keep, const clvr_tf *tf,
                                  clvr_error *err)
{
    if (g->cells == 0 || m->num_vertices == 0) return CLVR_OK;
    float *op = malloc(m->num_vertices * sizeof *op);
    if (!op) return clvr_error_set(err, CLVR_ERR_NO_MEMORY, "out of memory for the automatic density");
    const float w = tf->range_hi - tf->range_lo;
    for (uint64_t v = 0; v < m->num_vertices; ++v) {
        float s = m->scalars[v];
        op[v] = isnan(s) ? 0.0f : clvr_tf_opacity(tf, (s - tf->range_lo) / w);
    }
    const double ext_scale = (double)tf->density * clvr_tf_extinction_scale(tf);
    const double *lo = g->lo, *cell_h = g->cell_h;
    const int *n = g->n;
    /* Each element's extinction x volume, spread over its bounding box's cells. */
    uint64_t e = 0; /* element number across the types, for keep */
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) {
        const uint32_t nv = clvr_cell_vertex_count(t);
        for (uint64_t c = 0; c < m->num_cells[t]; ++c, ++e) {
            if (keep && !keep[e]) continue;
            const uint32_t *idx = m->indices[t] + c * nv;
            if ((c & 0xfffff) == 0xfffff) clvr_mesh_release_all_pages(m); /* a mapped .bin: pages back behind */
            double vol = fabs(clvr_scene_cell_volume(t, m->positions, idx));
            if (!(vol > 0.0) || !isfinite(vol)) continue;
            double a_sum = 0.0, bl[3] = {INFINITY, INFINITY, INFINITY}, bh[3] = {-INFINITY, -INFINITY, -INFINITY};
            for (uint32_t k = 0; k < nv; ++k) {
                a_sum += op[idx[k]];
                for (int a = 0; a < 3; ++a) {
                    double x = m->positions[3 * (uint64_t)idx[k] + a];
                    bl[a] = fmin(bl[a], x);
                    bh[a] = fmax(bh[a], x);
                }
            }
            if (!(a_sum > 0.0)) continue;
            /* Spread over the cells its box overlaps, in proportion to the
             * overlap along each axis (a box flat along an axis: all in its
             * cell there). An even share per touched cell instead left
             * cells that one element only grazes short of volume, and the
             * extinction of a mesh coarser than the grid 29% low (a box of
             * 0.1-wide hexes over cells of 0.042: test_tf_auto's exact
             * chords). */
            int i0[3], i1[3];
            double wt[3][PROBE_CELLS];
            for (int a = 0; a < 3; ++a) {
                double f0 = (bl[a] - lo[a]) / cell_h[a], f1 = (bh[a] - lo[a]) / cell_h[a];
                i0[a] = f0 <= 0.0 ? 0 : f0 >= n[a] - 1 ? n[a] - 1 : (int)f0;
                i1[a] = f1 <= 0.0 ? 0 : f1 >= n[a] - 1 ? n[a] - 1 : (int)f1;
                double sum = 0.0;
                for (int i = i0[a]; i <= i1[a]; ++i) {
                    const double c0 = (double)i, c1 = (double)(i + 1);
                    const double o = f1 > f0 ? fmin(f1, c1) - fmax(f0, c0) : 1.0;
                    wt[a][i - i0[a]] = o > 0.0 ? o : 0.0;
                    sum += wt[a][i - i0[a]];
                }
                /* Past the grid's ends (rounding) or no overlap at all: evenly. */
                for (int i = i0[a]; i <= i1[a]; ++i)
                    wt[a][i - i0[a]] = sum > 0.0 ? wt[a][i - i0[a]] / sum : 1.0 / (i1[a] - i0[a] + 1);
            }
            const double ext_vol = ext_scale * a_sum / nv * vol;
            for (int z = i0[2]; z <= i1[2]; ++z)
                for (int y = i0[1]; y <= i1[1]; ++y) {
                    const double wyz = wt[2][z - i0[2]] * wt[1][y - i0[1]];
                    for (int x = i0[0]; x <= i1[0]; ++x) {
                        const size_t i = ((size_t)z * n[1] + y) * n[0] + x;
                        const double share = wyz * wt[0][x - i0[0]];
                        g->sigma[i] += ext_vol * share;
                        g->covered[i] += vol * share;
                    }
                }
        }
    }
    free(op);
    return CLVR_OK;
}

clvr_status clvr_tf_auto_grid_median(const clvr_tf_auto_grid *g, float *median_depth, clvr_error *err)
{
    *median_depth = 0.0f;
    if (g->cells == 0) return CLVR_OK;
    const double *lo = g->lo, *ext = g->ext, *cell_h = g->cell_h;
    const int *n = g->n;
    const size_t cells = g->cells;
    const int rays_per_dir = PROBE_RAYS * PROBE_RAYS, dirs = 7;
    double *sigma = malloc(cells * sizeof *sigma);
    float *depth = malloc((size_t)rays_per_dir * dirs * sizeof *depth);
    if (!sigma || !depth) {
        free(sigma);
        free(depth);
        return clvr_error_set(err, CLVR_ERR_NO_MEMORY, "out of memory for the automatic density");
    }
    /* Extinction x volume over the cell's volume, or over the elements'
     * volume where they add up to more: overlapping elements (a mesh listed
     * twice) average, as the renderer shows one of them, instead of adding. */
    const double cell_vol = cell_h[0] * cell_h[1] * cell_h[2];
    for (size_t i = 0; i < cells; ++i) sigma[i] = g->sigma[i] / fmax(cell_vol, g->covered[i]);
    /* Parallel rays along the axes and the diagonals, midpoint steps of half a cell. */
    static const float dir_list[7][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 1}, {-1, 1, 1}, {1, -1, 1}, {1, 1, -1}};
    const double ctr[3] = {lo[0] + 0.5 * ext[0], lo[1] + 0.5 * ext[1], lo[2] + 0.5 * ext[2]};
    const double rad = 0.5 * sqrt(ext[0] * ext[0] + ext[1] * ext[1] + ext[2] * ext[2]);
    const double step = 0.5 * fmin(cell_h[0], fmin(cell_h[1], cell_h[2]));
    const int steps = (int)ceil(2.0 * rad / step);
    size_t nd = 0;
    float dmax = 0.0f;
    for (int di = 0; di < dirs; ++di) {
        double d[3] = {dir_list[di][0], dir_list[di][1], dir_list[di][2]}, u[3], v[3];
        double dl = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        for (int a = 0; a < 3; ++a) d[a] /= dl;
        /* u: perpendicular to d (cross with the axis d is least along). */
        int ax = fabs(d[0]) <= fabs(d[1]) && fabs(d[0]) <= fabs(d[2]) ? 0 : fabs(d[1]) <= fabs(d[2]) ? 1 : 2;
        double e[3] = {0, 0, 0};
        e[ax] = 1.0;
        u[0] = d[1] * e[2] - d[2] * e[1];
        u[1] = d[2] * e[0] - d[0] * e[2];
        u[2] = d[0] * e[1] - d[1] * e[0];
        double ul = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
        for (int a = 0; a < 3; ++a) u[a] /= ul;
        v[0] = d[1] * u[2] - d[2] * u[1];
        v[1] = d[2] * u[0] - d[0] * u[2];
        v[2] = d[0] * u[1] - d[1] * u[0];
        /* The box's extent across the rays. */
        double ur = 0.0, vr = 0.0;
        for (int a = 0; a < 3; ++a) {
            ur += 0.5 * ext[a] * fabs(u[a]);
            vr += 0.5 * ext[a] * fabs(v[a]);
        }
        for (int j = 0; j < PROBE_RAYS; ++j)
            for (int i = 0; i < PROBE_RAYS; ++i) {
                double cu = ur * (2.0 * (i + 0.5) / PROBE_RAYS - 1.0), cv = vr * (2.0 * (j + 0.5) / PROBE_RAYS - 1.0);
                double tau = 0.0;
                for (int s = 0; s < steps; ++s) {
                    double t = -rad + (s + 0.5) * step, c3[3];
                    int ok = 1;
                    size_t cell = 0;
                    for (int a = 2; a >= 0 && ok; --a) {
                        c3[a] = ctr[a] + cu * u[a] + cv * v[a] + t * d[a];
                        double f = (c3[a] - lo[a]) / cell_h[a];
                        if (!(f >= 0.0 && f < n[a])) ok = 0;
                        else cell = cell * (size_t)n[a] + (size_t)f;
                    }
                    if (ok) tau += sigma[cell] * step;
                }
                depth[nd++] = (float)tau;
                if ((float)tau > dmax) dmax = (float)tau;
            }
    }
    size_t k = 0;
    for (size_t i = 0; i < nd; ++i)
        if (depth[i] > 1e-3f * dmax && dmax > 0.0f) depth[k++] = depth[i];
    if (k > 0) {
        qsort(depth, k, sizeof *depth, cmp_float);
        *median_depth = k % 2 ? depth[k / 2] : 0.5f * (depth[k / 2 - 1] + depth[k / 2]);
    }
    free(sigma);
    free(depth);
    return CLVR_OK;
}


clvr_status clvr_tf_auto_probe(const clvr_mesh *m, const clvr_tf *tf, float *median_depth, clvr_error *err)
{
    *median_depth = 0.0f;
    if (m->num_vertices == 0) return CLVR_OK;
    clvr_tf_auto_grid g;
    clvr_status s = clvr_tf_auto_grid_create(m->bounds_lo, m->bounds_hi, &g, err);
    if (s == CLVR_OK) s = clvr_tf_auto_grid_add(&g, m, NULL, tf, err);
    if (s == CLVR_OK) s = clvr_tf_auto_grid_median(&g, median_depth, err);
    clvr_tf_auto_grid_free(&g);
    return s;
}

clvr_status clvr_tf_auto_density(const clvr_mesh *m, const clvr_tf *tf, float *density, clvr_error *err)
{
    clvr_tf unit = *tf; /* shallow: the probe only reads the points */
    unit.density = 1.0f;
    float med = 0.0f;
    clvr_status s = clvr_tf_auto_probe(m, &unit, &med, err);
    if (s != CLVR_OK) return s;
    *density = clvr_tf_auto_density_of_median(med);
    return CLVR_OK;
}

float clvr_tf_auto_density_of_median(float median_depth)
{
    float d = median_depth > 0.0f ? CLVR_TF_AUTO_DEPTH / median_depth : 1.0f;
    return d < 1e-3f ? 1e-3f : d > 1e4f ? 1e4f : d;
}
