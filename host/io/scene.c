/* scene.c: the built-in scene and parametrised box meshes; see scene.h for
 * the tiling scheme and the vertex numbering. */
#include "scene.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Cube corners in VTK hexahedron order, as (x, y, z) offsets. */
static const uint8_t corner_offset[8][3] = {
    {0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};

/* Kuhn / Freudenthal split: one tet per ordering of the three axis steps
 * from corner 0 to corner 6, vertex order fixed so each has positive volume.
 * Translation-invariant, so the face diagonals of neighbouring tet cubes
 * coincide (conforming, also under jitter). */
static const uint8_t kuhn_tets[6][4] = {{0, 1, 2, 6}, {0, 1, 6, 5}, {0, 3, 6, 2},
                                        {0, 3, 7, 6}, {0, 4, 5, 6}, {0, 4, 6, 7}};

/* Two wedges split by the plane through edges 0-4 and 2-6. VTK's wedge has
 * the normal of (0,1,2) pointing away from (3,4,5), hence the clockwise
 * bottom triangles. */
static const uint8_t cube_wedges[2][6] = {{0, 2, 1, 4, 6, 5}, {0, 3, 2, 4, 7, 6}};

/* Six pyramids: each cube face, ordered so its normal points inward (to the
 * apex, VTK's pyramid convention), plus the centre vertex (slot 8). */
static const uint8_t cube_pyramids[6][5] = {{3, 7, 4, 0, 8}, {5, 6, 2, 1, 8}, {4, 5, 1, 0, 8},
                                            {2, 6, 7, 3, 8}, {1, 2, 3, 0, 8}, {7, 6, 5, 4, 8}};

/* Outward faces per type in VTK order (vtkCell::GetFace lists); -1 ends a triangle. */
static const int8_t tet_faces[4][4] = {{0, 1, 3, -1}, {1, 2, 3, -1}, {2, 0, 3, -1}, {0, 2, 1, -1}};
static const int8_t pyr_faces[5][4] = {{0, 3, 2, 1}, {0, 1, 4, -1}, {1, 2, 4, -1}, {2, 3, 4, -1}, {3, 0, 4, -1}};
static const int8_t wedge_faces[5][4] = {{0, 1, 2, -1}, {3, 5, 4, -1}, {0, 3, 4, 1}, {1, 4, 5, 2}, {2, 5, 3, 0}};
static const int8_t hex_faces[6][4] = {{0, 4, 7, 3}, {1, 2, 6, 5}, {0, 1, 5, 4},
                                       {3, 7, 6, 2}, {0, 3, 2, 1}, {4, 5, 6, 7}};

/* Elements per cube of each split. */
static const uint32_t split_cells[4] = {6, 6, 2, 1}; /* by CLVR_CELL_*: tet, pyramid, wedge, hex */

static uint64_t splitmix64(uint64_t x)
{
    x += 0x9e3779b97f4a7c15ull;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
    return x ^ (x >> 31);
}

/* Gaussian of squared distance d2 with standard deviation sigma. */
static float gauss(float d2, float sigma) { return expf(-d2 / (2.0f * sigma * sigma)); }

float clvr_scene_blobs(const float u[3])
{
    const float x = u[0], y = u[1], z = u[2];
    /* Vortex ring: Gaussian tube around a circle of radius 0.25 at z = 0.3. */
    float dxr = x - 0.5f, dyr = y - 0.5f, dzr = z - 0.3f;
    float rho = sqrtf(dxr * dxr + dyr * dyr) - 0.25f;
    float f = gauss(rho * rho + dzr * dzr, 0.05f);
    /* Flame: a plume rising from the ring's centre, swaying and thinning
     * with height, strongest near its base. */
    if (z > 0.25f) {
        float h = (z - 0.25f) / 0.7f; /* 0 at the base, 1 at z = 0.95 */
        float cx = 0.5f + 0.06f * sinf(10.0f * z), cy = 0.5f + 0.04f * cosf(7.0f * z);
        float sigma = 0.07f * (1.0f - 0.7f * fminf(h, 1.0f));
        float dx = x - cx, dy = y - cy;
        float ramp = fminf(1.0f, (z - 0.25f) / 0.08f) * expf(-2.0f * h * h);
        f += 0.9f * ramp * gauss(dx * dx + dy * dy, sigma);
    }
    /* Two blobs off to the sides. */
    {
        float dx = x - 0.2f, dy = y - 0.75f, dz = z - 0.7f;
        f += 0.8f * gauss(dx * dx + dy * dy + dz * dz, 0.07f);
    }
    {
        float dx = x - 0.8f, dy = y - 0.25f, dz = z - 0.6f;
        f += 0.6f * gauss(dx * dx + dy * dy + dz * dz, 0.09f);
    }
    return fminf(f, 1.0f);
}

void clvr_scene_box_params_init(clvr_scene_box_params *p)
{
    memset(p, 0, sizeof *p);
    p->nx = p->ny = p->nz = 10;
    p->hi[0] = p->hi[1] = p->hi[2] = 1.0f;
    p->mix = CLVR_SCENE_MIX_HEX;
    p->field = CLVR_SCENE_FIELD_CONSTANT;
    p->value = 1.0f;
}

clvr_status clvr_scene_box_check(const clvr_scene_box_params *p, clvr_error *err)
{
    if (p->nx < 1 || p->ny < 1 || p->nz < 1)
        return clvr_error_set(err, CLVR_ERR_USAGE, "scene box: nx, ny, nz are %u, %u, %u; each must be >= 1",
                              p->nx, p->ny, p->nz);
    if (p->nx > (1u << 21) || p->ny > (1u << 21) || p->nz > (1u << 21))
        return clvr_error_set(err, CLVR_ERR_USAGE, "scene box: nx, ny, nz are %u, %u, %u; each must be <= 2^21",
                              p->nx, p->ny, p->nz);
    for (int a = 0; a < 3; ++a)
        if (!(p->lo[a] < p->hi[a]) || !isfinite(p->lo[a]) || !isfinite(p->hi[a]))
            return clvr_error_set(err, CLVR_ERR_USAGE, "scene box: axis %d has lo %g, hi %g; need finite lo < hi", a,
                                  (double)p->lo[a], (double)p->hi[a]);
    if ((unsigned)p->mix >= CLVR_SCENE_MIX_COUNT)
        return clvr_error_set(err, CLVR_ERR_USAGE, "scene box: mix %d is not a clvr_scene_mix", (int)p->mix);
    if ((unsigned)p->field >= CLVR_SCENE_FIELD_COUNT)
        return clvr_error_set(err, CLVR_ERR_USAGE, "scene box: field %d is not a clvr_scene_field", (int)p->field);
    if (!(p->jitter >= 0.0f && p->jitter <= 0.25f))
        return clvr_error_set(err, CLVR_ERR_USAGE, "scene box: jitter %g is outside [0, 0.25]", (double)p->jitter);
    if (p->jitter > 0.0f && (p->mix == CLVR_SCENE_MIX_MIXED || p->mix == CLVR_SCENE_MIX_CYCLE))
        return clvr_error_set(err, CLVR_ERR_USAGE,
                              "scene box: jitter %g with a mixed split would leave gaps between cubes of different "
                              "types; use jitter 0 or a single-type mix",
                              (double)p->jitter);
    if (!isfinite(p->value))
        return clvr_error_set(err, CLVR_ERR_USAGE, "scene box: constant value is not finite");
    return CLVR_OK;
}

/* Position of lattice vertex (i, j, k), jittered when it is interior.
 * Computed from integers only, so every caller gets the same float. */
static void lattice_pos(const clvr_scene_box_params *p, uint32_t i, uint32_t j, uint32_t k, float out[3])
{
    const uint32_t n[3] = {p->nx, p->ny, p->nz}, ijk[3] = {i, j, k};
    int interior = i > 0 && i < p->nx && j > 0 && j < p->ny && k > 0 && k < p->nz;
    uint64_t h = 0;
    if (interior && p->jitter > 0.0f)
        h = splitmix64(p->seed ^ splitmix64(((uint64_t)k * (p->ny + 1u) + j) * (p->nx + 1u) + i));
    for (int a = 0; a < 3; ++a) {
        double t = (double)ijk[a] / (double)n[a];
        if (h) {
            /* 21 random bits per axis mapped to [-1, 1). */
            double r = (double)((h >> (21 * a)) & 0x1fffffu) / (double)(1u << 20) - 1.0;
            t += r * (double)p->jitter / (double)n[a];
        }
        out[a] = (float)((double)p->lo[a] + t * ((double)p->hi[a] - (double)p->lo[a]));
    }
}

static float field_at(const clvr_scene_box_params *p, const float x[3])
{
    switch (p->field) {
    case CLVR_SCENE_FIELD_RAMP_X: return (x[0] - p->lo[0]) / (p->hi[0] - p->lo[0]);
    case CLVR_SCENE_FIELD_BLOBS: {
        float u[3];
        for (int a = 0; a < 3; ++a) u[a] = (x[a] - p->lo[a]) / (p->hi[a] - p->lo[a]);
        return clvr_scene_blobs(u);
    }
    default: return p->value;
    }
}

/* The CLVR_CELL_* type that cube (i, j, k) is split into. */
static uint32_t cube_type(const clvr_scene_box_params *p, uint32_t i, uint32_t j, uint32_t k)
{
    switch (p->mix) {
    case CLVR_SCENE_MIX_HEX: return CLVR_CELL_HEX;
    case CLVR_SCENE_MIX_TET: return CLVR_CELL_TET;
    case CLVR_SCENE_MIX_WEDGE: return CLVR_CELL_WEDGE;
    case CLVR_SCENE_MIX_PYRAMID: return CLVR_CELL_PYRAMID;
    case CLVR_SCENE_MIX_CYCLE: {
        static const uint32_t order[4] = {CLVR_CELL_HEX, CLVR_CELL_TET, CLVR_CELL_WEDGE, CLVR_CELL_PYRAMID};
        return order[(i + j + k) % 4u];
    }
    default: {
        float u[3] = {((float)i + 0.5f) / (float)p->nx, ((float)j + 0.5f) / (float)p->ny,
                      ((float)k + 0.5f) / (float)p->nz};
        float f = clvr_scene_blobs(u);
        return f >= 0.35f ? CLVR_CELL_TET : f >= 0.12f ? CLVR_CELL_PYRAMID : f >= 0.03f ? CLVR_CELL_WEDGE : CLVR_CELL_HEX;
    }
    }
}

clvr_status clvr_scene_box_count(const clvr_scene_box_params *p, uint64_t *num_vertices,
                                 uint64_t num_cells[CLVR_CELL_TYPE_COUNT], clvr_error *err)
{
    clvr_status s = clvr_scene_box_check(p, err);
    if (s != CLVR_OK) return s;
    uint64_t cubes_of[CLVR_CELL_TYPE_COUNT] = {0};
    const uint64_t cubes = (uint64_t)p->nx * p->ny * p->nz;
    const uint64_t lattice = (uint64_t)(p->nx + 1u) * (p->ny + 1u) * (p->nz + 1u);
    /* Checked before the cube loop, which would take long on absurd sizes. */
    if (lattice > UINT32_MAX)
        return clvr_error_set(err, CLVR_ERR_OVERFLOW,
                              "scene box: %u x %u x %u cubes need %llu lattice vertices, more than 32-bit indices "
                              "address; use fewer cubes",
                              p->nx, p->ny, p->nz, (unsigned long long)lattice);
    if (p->mix == CLVR_SCENE_MIX_MIXED || p->mix == CLVR_SCENE_MIX_CYCLE) {
        for (uint32_t k = 0; k < p->nz; ++k)
            for (uint32_t j = 0; j < p->ny; ++j)
                for (uint32_t i = 0; i < p->nx; ++i) ++cubes_of[cube_type(p, i, j, k)];
    } else {
        cubes_of[cube_type(p, 0, 0, 0)] = cubes;
    }
    uint64_t verts = lattice + cubes_of[CLVR_CELL_PYRAMID];
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) num_cells[t] = cubes_of[t] * split_cells[t];
    if (verts > UINT32_MAX)
        return clvr_error_set(err, CLVR_ERR_OVERFLOW,
                              "scene box: %u x %u x %u cubes need %llu vertices, more than 32-bit indices address; "
                              "use fewer cubes",
                              p->nx, p->ny, p->nz, (unsigned long long)verts);
    *num_vertices = verts;
    return CLVR_OK;
}

void clvr_scene_box_layer(const clvr_scene_box_params *p, uint32_t k, float *xyz, float *s)
{
    size_t v = 0;
    for (uint32_t j = 0; j <= p->ny; ++j)
        for (uint32_t i = 0; i <= p->nx; ++i, ++v) {
            lattice_pos(p, i, j, k, xyz + 3 * v);
            s[v] = field_at(p, xyz + 3 * v);
        }
}

void clvr_scene_box_slab_bound(const clvr_scene_box_params *p, uint64_t max_cells[CLVR_CELL_TYPE_COUNT],
                               uint64_t *max_centres)
{
    const uint64_t layer = (uint64_t)p->nx * p->ny;
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) max_cells[t] = layer * split_cells[t];
    *max_centres = layer;
}

void clvr_scene_box_slab(const clvr_scene_box_params *p, uint32_t k, uint64_t first_centre,
                         uint32_t *cells[CLVR_CELL_TYPE_COUNT], uint64_t num_cells[CLVR_CELL_TYPE_COUNT],
                         float *centre_xyz, float *centre_s, uint64_t *num_centres)
{
    const uint64_t sx = 1, sy = (uint64_t)p->nx + 1u, sz = sy * ((uint64_t)p->ny + 1u);
    uint64_t nc = 0;
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) num_cells[t] = 0;
    for (uint32_t j = 0; j < p->ny; ++j)
        for (uint32_t i = 0; i < p->nx; ++i) {
            uint32_t v[9];
            for (int c = 0; c < 8; ++c)
                v[c] = (uint32_t)((i + corner_offset[c][0]) * sx + (j + corner_offset[c][1]) * sy +
                                  (k + corner_offset[c][2]) * sz);
            const uint32_t t = cube_type(p, i, j, k);
            uint32_t *out = cells[t] + num_cells[t] * clvr_cell_vertex_count(t);
            switch (t) {
            case CLVR_CELL_HEX:
                for (int c = 0; c < 8; ++c) out[c] = v[c];
                break;
            case CLVR_CELL_TET:
                for (int e = 0; e < 6; ++e)
                    for (int c = 0; c < 4; ++c) out[4 * e + c] = v[kuhn_tets[e][c]];
                break;
            case CLVR_CELL_WEDGE:
                for (int e = 0; e < 2; ++e)
                    for (int c = 0; c < 6; ++c) out[6 * e + c] = v[cube_wedges[e][c]];
                break;
            default: {
                /* The apex: centroid of the (possibly jittered) corners. */
                float *x = centre_xyz + 3 * nc, corner[3];
                x[0] = x[1] = x[2] = 0.0f;
                for (int c = 0; c < 8; ++c) {
                    lattice_pos(p, i + corner_offset[c][0], j + corner_offset[c][1], k + corner_offset[c][2],
                                corner);
                    for (int a = 0; a < 3; ++a) x[a] += 0.125f * corner[a];
                }
                centre_s[nc] = field_at(p, x);
                v[8] = (uint32_t)(first_centre + nc);
                ++nc;
                for (int e = 0; e < 6; ++e)
                    for (int c = 0; c < 5; ++c) out[5 * e + c] = v[cube_pyramids[e][c]];
                break;
            }
            }
            num_cells[t] += split_cells[t];
        }
    *num_centres = nc;
}

clvr_status clvr_scene_box(const clvr_scene_box_params *p, clvr_mesh *out, clvr_error *err)
{
    uint64_t nv, counts[CLVR_CELL_TYPE_COUNT];
    memset(out, 0, sizeof *out);
    clvr_status s = clvr_scene_box_count(p, &nv, counts, err);
    if (s != CLVR_OK) return s;
    s = clvr_mesh_alloc(out, nv, counts, err);
    if (s != CLVR_OK) return s;

    const uint64_t layer_verts = ((uint64_t)p->nx + 1u) * ((uint64_t)p->ny + 1u);
    for (uint32_t k = 0; k <= p->nz; ++k)
        clvr_scene_box_layer(p, k, out->positions + 3 * k * layer_verts, out->scalars + k * layer_verts);

    uint64_t centre = layer_verts * ((uint64_t)p->nz + 1u);
    uint64_t done[CLVR_CELL_TYPE_COUNT] = {0};
    for (uint32_t k = 0; k < p->nz; ++k) {
        uint32_t *cells[CLVR_CELL_TYPE_COUNT];
        uint64_t got[CLVR_CELL_TYPE_COUNT], nc;
        for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t)
            cells[t] = out->indices[t] ? out->indices[t] + done[t] * clvr_cell_vertex_count(t) : NULL;
        clvr_scene_box_slab(p, k, centre, cells, got, out->positions + 3 * centre, out->scalars + centre, &nc);
        for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) done[t] += got[t];
        centre += nc;
    }
    snprintf(out->scalar_name, sizeof out->scalar_name, "%s",
             p->field == CLVR_SCENE_FIELD_BLOBS ? "blobs" : p->field == CLVR_SCENE_FIELD_RAMP_X ? "ramp_x" : "constant");
    clvr_mesh_update_ranges(out);
    return CLVR_OK;
}

clvr_status clvr_scene_default(clvr_mesh *out, clvr_error *err)
{
    clvr_scene_box_params p;
    clvr_scene_box_params_init(&p);
    p.nx = p.ny = p.nz = 56;
    for (int a = 0; a < 3; ++a) {
        p.lo[a] = -1.0f;
        p.hi[a] = 1.0f;
    }
    p.mix = CLVR_SCENE_MIX_MIXED;
    p.field = CLVR_SCENE_FIELD_BLOBS;
    return clvr_scene_box(&p, out, err);
}

/* Signed volume of the cone from c over triangle (a, b, d) oriented outward. */
static double cone(const double c[3], const double a[3], const double b[3], const double d[3])
{
    double u[3], v[3], w[3];
    for (int i = 0; i < 3; ++i) {
        u[i] = a[i] - c[i];
        v[i] = b[i] - c[i];
        w[i] = d[i] - c[i];
    }
    return (u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) + u[2] * (v[0] * w[1] - v[1] * w[0])) /
           6.0;
}

double clvr_scene_cell_volume(uint32_t type, const float *positions, const uint32_t *idx)
{
    const int8_t(*faces)[4];
    int nf;
    switch (type) {
    case CLVR_CELL_TET: faces = tet_faces; nf = 4; break;
    case CLVR_CELL_PYRAMID: faces = pyr_faces; nf = 5; break;
    case CLVR_CELL_WEDGE: faces = wedge_faces; nf = 5; break;
    default: faces = hex_faces; nf = 6; break;
    }
    const uint32_t nv = clvr_cell_vertex_count(type);
    double x[CLVR_CELL_MAX_VERTS][3], c[3] = {0, 0, 0};
    for (uint32_t v = 0; v < nv; ++v)
        for (int a = 0; a < 3; ++a) {
            x[v][a] = positions[3 * (uint64_t)idx[v] + a];
            c[a] += x[v][a] / nv;
        }
    double vol = 0.0;
    for (int f = 0; f < nf; ++f) {
        if (faces[f][3] < 0) {
            vol += cone(c, x[faces[f][0]], x[faces[f][1]], x[faces[f][2]]);
        } else {
            double m[3];
            for (int a = 0; a < 3; ++a)
                m[a] = 0.25 * (x[faces[f][0]][a] + x[faces[f][1]][a] + x[faces[f][2]][a] + x[faces[f][3]][a]);
            for (int e = 0; e < 4; ++e) vol += cone(c, x[faces[f][e]], x[faces[f][(e + 1) % 4]], m);
        }
    }
    return vol;
}
