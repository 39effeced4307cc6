/* mpi_load.c: a rank's share of a .bin mesh, read with offsets (see
 * mpi_load.h and docs/mpi-loading.md).
 *
 * Every step that can fail on one rank ends with clvr_mpi_agree before the
 * next collective, so a failure anywhere becomes the same error everywhere
 * and no rank waits in a collective that another has left. All sizes are
 * 64-bit; MPI's int counts only ever see one bounded round of an exchange
 * (xchg below). */
#include "mpi_load.h"

#include <errno.h>
#include <fcntl.h>
#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#define LOAD_SAMPLE_MAX 65536u                 /* centroids bisected for the regions */
#define LOAD_CHUNK_DEFAULT ((uint64_t)16 << 20) /* bytes of element records per round, all peers */
#define LOAD_CHUNK_MAX ((uint64_t)1 << 30)      /* keeps a round's byte counts below INT_MAX */
#define LOAD_IO_CHUNK ((uint64_t)1 << 30)       /* largest single pread */
#define LOAD_TUPLE_CHUNK 65536u                 /* tuples per read of a multi-component field */
#define REC_HEAD 1u                             /* element record: the type, then the global indices; records
                                                * arrive in file order, so no element id is sent */

clvr_status clvr_mpi_agree(MPI_Comm comm, clvr_status local, clvr_error *err)
{
    int rank, size;
    MPI_Comm_rank(comm, &rank);
    MPI_Comm_size(comm, &size);
    int mine[2] = {local == CLVR_OK ? INT_MAX : rank, local == CLVR_OK ? 0 : 1}, all[2];
    MPI_Allreduce(&mine[0], &all[0], 1, MPI_INT, MPI_MIN, comm);
    MPI_Allreduce(&mine[1], &all[1], 1, MPI_INT, MPI_SUM, comm);
    if (all[0] == INT_MAX) return CLVR_OK;
    struct {
        int status;
        char msg[sizeof err->msg];
    } b;
    memset(&b, 0, sizeof b);
    if (rank == all[0]) {
        b.status = (int)local;
        if (err && err->msg[0]) memcpy(b.msg, err->msg, sizeof b.msg - 1);
        else snprintf(b.msg, sizeof b.msg, "%s", clvr_status_text(local));
    }
    MPI_Bcast(&b, (int)sizeof b, MPI_BYTE, all[0], comm);
    b.msg[sizeof b.msg - 1] = '\0';
    char others[64] = "";
    if (all[1] > 1) snprintf(others, sizeof others, " (and %d other rank%s)", all[1] - 1, all[1] > 2 ? "s" : "");
    return clvr_error_set(err, (clvr_status)b.status, "rank %d of %d%s: %s", all[0], size, others, b.msg);
}

/* ------------------------------------------------------------ helpers */

/* Rank r's contiguous part of n items: the first n % size ranks get one
 * more. No product of n and r, so no overflow at any count. */
static void slice_of(uint64_t n, int r, int size, uint64_t *first, uint64_t *count)
{
    const uint64_t q = n / (uint64_t)size, rem = n % (uint64_t)size, ur = (uint64_t)r;
    *first = q * ur + (ur < rem ? ur : rem);
    *count = q + (ur < rem ? 1u : 0u);
}

static int slice_owner(uint64_t i, uint64_t n, int size)
{
    const uint64_t q = n / (uint64_t)size, rem = n % (uint64_t)size, big = rem * (q + 1);
    if (i < big) return (int)(i / (q + 1));
    return (int)(rem + (i - big) / q); /* q > 0 here: i < n and i >= big = n when q = 0 */
}

/* LSD radix sort of u32 keys (11 bits a pass) with scratch of n; then
 * duplicates removed. Returns the unique count. */
static uint64_t sort_unique_u32(uint32_t *a, uint32_t *tmp, uint64_t n)
{
    uint32_t *src = a, *dst = tmp;
    for (int shift = 0; shift < 32; shift += 11) {
        uint64_t count[2048] = {0};
        for (uint64_t i = 0; i < n; ++i) ++count[(src[i] >> shift) & 2047u];
        uint64_t sum = 0;
        for (int b = 0; b < 2048; ++b) {
            uint64_t c = count[b];
            count[b] = sum;
            sum += c;
        }
        for (uint64_t i = 0; i < n; ++i) dst[count[(src[i] >> shift) & 2047u]++] = src[i];
        uint32_t *t = src;
        src = dst;
        dst = t;
    }
    /* Three passes: the sorted keys are in tmp. */
    uint64_t u = 0;
    for (uint64_t i = 0; i < n; ++i)
        if (u == 0 || src[i] != a[u - 1]) a[u++] = src[i];
    return u;
}

/* Position of a key in sorted distinct ids[0..n) (present by
 * construction): a bucket table over the id range (about one bucket per
 * two ids, one word each) narrows a binary search to a few entries, which
 * matters at one lookup per element corner. */
typedef struct id_index {
    const uint32_t *ids;
    uint64_t n;
    uint32_t min;
    int shift;
    uint64_t nb;
    uint32_t *start; /* nb + 1: first position of each bucket; positions < n < 2^32 */
} id_index;

static int id_index_build(id_index *x, const uint32_t *ids, uint64_t n)
{
    memset(x, 0, sizeof *x);
    x->ids = ids;
    x->n = n;
    if (n == 0) return 0;
    x->min = ids[0];
    const uint64_t span = (uint64_t)ids[n - 1] - ids[0] + 1;
    while ((span >> x->shift) > n / 2 + 1) ++x->shift;
    x->nb = (span >> x->shift) + 1;
    x->start = malloc((size_t)(x->nb + 1) * sizeof *x->start);
    if (!x->start) return 1;
    uint64_t i = 0;
    for (uint64_t b = 0; b <= x->nb; ++b) {
        const uint64_t lo = (uint64_t)x->min + (b << x->shift);
        while (i < n && ids[i] < lo) ++i;
        x->start[b] = (uint32_t)i;
    }
    return 0;
}

static uint64_t id_index_find(const id_index *x, uint32_t key)
{
    const uint64_t b = (uint64_t)(key - x->min) >> x->shift;
    uint64_t lo = x->start[b], hi = x->start[b + 1];
    while (hi - lo > 1) {
        uint64_t mid = lo + (hi - lo) / 2;
        if (x->ids[mid] <= key) lo = mid;
        else hi = mid;
    }
    return lo;
}

static void *alloc_items(uint64_t n, size_t item)
{
    if (n > SIZE_MAX / item) return NULL;
    return malloc(n ? (size_t)(n * item) : 1);
}

/* The distinct values of the index lists idx[t][0..n[t]), sorted, in
 * *out (malloc, *nout entries). An open-addressing set first (vertex
 * indices are below 2^32 - 1, so UINT32_MAX marks an empty slot), then a
 * radix sort of the distinct ids only: each vertex is used by several
 * elements, so this needs a fraction of the memory that sorting every
 * corner would. Nonzero when out of memory. */
static int distinct_ids(uint32_t *const idx[CLVR_CELL_TYPE_COUNT], const uint64_t n[CLVR_CELL_TYPE_COUNT],
                        uint32_t **out, uint64_t *nout)
{
    /* Start at a quarter of the corners (hexes share each vertex among up
     * to 8, tets among ~24), so that most sets never grow. */
    uint64_t corners = 0, cap = 1u << 12, used = 0;
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) corners += n[t];
    while (cap < corners / 4 && cap < ((uint64_t)1 << 33)) cap *= 2;
    uint32_t *set = cap <= SIZE_MAX / sizeof *set ? malloc((size_t)cap * sizeof *set) : NULL;
    *out = NULL;
    *nout = 0;
    if (!set) return 1;
    memset(set, 0xff, (size_t)cap * sizeof *set);
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t)
        for (uint64_t i = 0; i < n[t]; ++i) {
            const uint32_t v = idx[t][i];
            uint64_t h = ((uint64_t)v * 0x9e3779b97f4a7c15ull) >> 20 & (cap - 1);
            while (set[h] != UINT32_MAX && set[h] != v) h = (h + 1) & (cap - 1);
            if (set[h] == v) continue;
            set[h] = v;
            if (++used * 2 <= cap) continue;
            /* Grow: rehash into twice the slots. */
            uint64_t ncap = cap * 2;
            uint32_t *ns = ncap <= SIZE_MAX / sizeof *ns ? malloc((size_t)ncap * sizeof *ns) : NULL;
            if (!ns) {
                free(set);
                return 1;
            }
            memset(ns, 0xff, (size_t)ncap * sizeof *ns);
            for (uint64_t k = 0; k < cap; ++k) {
                if (set[k] == UINT32_MAX) continue;
                uint64_t g = ((uint64_t)set[k] * 0x9e3779b97f4a7c15ull) >> 20 & (ncap - 1);
                while (ns[g] != UINT32_MAX) g = (g + 1) & (ncap - 1);
                ns[g] = set[k];
            }
            free(set);
            set = ns;
            cap = ncap;
        }
    /* Compact in place, then sort with scratch of the distinct count. */
    uint64_t k = 0;
    for (uint64_t i = 0; i < cap; ++i)
        if (set[i] != UINT32_MAX) set[k++] = set[i];
    uint32_t *tmp = malloc(k ? (size_t)k * sizeof *tmp : 1);
    if (!tmp) {
        free(set);
        return 1;
    }
    *nout = sort_unique_u32(set, tmp, k);
    free(tmp);
    uint32_t *shrunk = realloc(set, k ? (size_t)k * sizeof *set : 1);
    *out = shrunk ? shrunk : set;
    return 0;
}

typedef struct load_ctx {
    MPI_Comm comm;
    int rank, size;
    const char *path;
    int fd;
    int staged; /* exchanges always go through bounded scratch (an explicit chunk size) */
    clvr_bin_layout lay;
    uint64_t chunk_bytes;
    clvr_mpi_load_stats st;
    uint64_t num_elements;
    uint64_t type_first[CLVR_CELL_TYPE_COUNT]; /* global id of each type's first element */
    clvr_error e;                              /* this rank's own message until agreed */
} load_ctx;

static clvr_status read_at(load_ctx *c, uint64_t off, void *dst, uint64_t n, const char *what)
{
    uint8_t *p = (uint8_t *)dst;
    while (n > 0) {
        size_t want = (size_t)(n < LOAD_IO_CHUNK ? n : LOAD_IO_CHUNK);
        if (off > (uint64_t)INT64_MAX)
            return clvr_error_set(&c->e, CLVR_ERR_IO, "%s: offset %llu of %s is beyond what the OS can address",
                                  c->path, (unsigned long long)off, what);
        ssize_t got = pread(c->fd, p, want, (off_t)off);
        if (got < 0 && errno == EINTR) continue;
        if (got < 0) return clvr_error_set(&c->e, CLVR_ERR_IO, "%s: cannot read %s: %s", c->path, what, strerror(errno));
        if (got == 0)
            return clvr_error_set(&c->e, CLVR_ERR_TRUNCATED, "%s: truncated while reading %s (the file shrank?)",
                                  c->path, what);
        p += got;
        n -= (uint64_t)got;
        off += (uint64_t)got;
        c->st.bytes_read += (uint64_t)got;
    }
    return CLVR_OK;
}

static clvr_status agree(load_ctx *c, clvr_status s)
{
    return clvr_mpi_agree(c->comm, s, &c->e);
}

/* ------------------------------------------------------------ exchange */

/* MPI_Alltoall of 64-bit counts. */
static void xchg_counts(load_ctx *c, const uint64_t *send, uint64_t *recv)
{
    MPI_Alltoall((void *)send, 1, MPI_UINT64_T, recv, 1, MPI_UINT64_T, c->comm);
}

/* Alltoallv of items of `item` bytes with 64-bit counts: scount[d] items
 * for rank d, packed in rank order in sendbuf; rcount[s] from rank s into
 * recvbuf in rank order (the caller sized it and agreed). Rounds of at
 * most max(1, chunk / item / size) items per peer, packed into bounded
 * scratch, so int counts and displacements never overflow. Collective;
 * allocates scratch and agrees before the first round. */
static clvr_status xchg(load_ctx *c, const void *sendbuf, const uint64_t *scount, void *recvbuf,
                        const uint64_t *rcount, size_t item)
{
    const int n = c->size;
    /* Direct: one datatype of `item` bytes, counts and displacements in
     * items straight on the caller's buffers, while they fit an int.
     * Staged (c->staged, or beyond int): bounded scratch per round. */
    uint64_t per = c->staged ? c->chunk_bytes / item / (uint64_t)n : (uint64_t)INT_MAX / 2;
    if (per == 0) per = 1;
    uint64_t rounds = 0, mine = 0;
    for (int d = 0; d < n; ++d) {
        uint64_t a = (scount[d] + per - 1) / per, b = (rcount[d] + per - 1) / per;
        if (a > mine) mine = a;
        if (b > mine) mine = b;
    }
    uint64_t stot = 0, rtot = 0;
    for (int d = 0; d < n; ++d) {
        stot += scount[d];
        rtot += rcount[d];
    }
    uint64_t need_stage = !c->staged && (stot >= (uint64_t)INT_MAX || rtot >= (uint64_t)INT_MAX), red[2] = {mine, need_stage}, got[2];
    MPI_Allreduce(red, got, 2, MPI_UINT64_T, MPI_MAX, c->comm);
    rounds = got[0];
    const int staged = c->staged || got[1];
    if (!c->staged && got[1]) { /* some rank's buffers pass INT_MAX items: everyone rounds through scratch */
        per = c->chunk_bytes / item / (uint64_t)n;
        if (per == 0) per = 1;
        mine = 0;
        for (int d = 0; d < n; ++d) {
            uint64_t a = (scount[d] + per - 1) / per, b = (rcount[d] + per - 1) / per;
            if (a > mine) mine = a;
            if (b > mine) mine = b;
        }
        MPI_Allreduce(&mine, &rounds, 1, MPI_UINT64_T, MPI_MAX, c->comm);
    }
    uint64_t *sdisp = calloc((size_t)n, sizeof *sdisp), *rdisp = calloc((size_t)n, sizeof *rdisp);
    int *sc = calloc((size_t)n, sizeof *sc), *rc = calloc((size_t)n, sizeof *rc);
    int *sd = calloc((size_t)n, sizeof *sd), *rd = calloc((size_t)n, sizeof *rd);
    uint64_t sbytes = 0, rbytes = 0;
    for (int d = 0; d < n && staged; ++d) {
        uint64_t a = scount[d] < per ? scount[d] : per, b = rcount[d] < per ? rcount[d] : per;
        sbytes += a * item;
        rbytes += b * item;
    }
    uint8_t *stmp = malloc(sbytes ? (size_t)sbytes : 1), *rtmp = malloc(rbytes ? (size_t)rbytes : 1);
    MPI_Datatype type;
    MPI_Type_contiguous((int)item, MPI_BYTE, &type);
    MPI_Type_commit(&type);
    clvr_status s = CLVR_OK;
    if (!sdisp || !rdisp || !sc || !rc || !sd || !rd || !stmp || !rtmp)
        s = clvr_error_set(&c->e, CLVR_ERR_NO_MEMORY, "%s: cannot allocate %llu bytes of exchange buffers", c->path,
                           (unsigned long long)(sbytes + rbytes));
    s = agree(c, s);
    if (s == CLVR_OK) {
        for (int d = 1; d < n; ++d) {
            sdisp[d] = sdisp[d - 1] + scount[d - 1];
            rdisp[d] = rdisp[d - 1] + rcount[d - 1];
        }
        for (uint64_t k = 0; k < rounds && !staged; ++k) {
            const uint64_t base = k * per;
            for (int d = 0; d < n; ++d) {
                uint64_t a = scount[d] > base ? scount[d] - base : 0, b = rcount[d] > base ? rcount[d] - base : 0;
                sc[d] = (int)(a < per ? a : per);
                rc[d] = (int)(b < per ? b : per);
                sd[d] = (int)(sdisp[d] + base); /* < stot < INT_MAX */
                rd[d] = (int)(rdisp[d] + base);
            }
            MPI_Alltoallv((void *)sendbuf, sc, sd, type, recvbuf, rc, rd, type, c->comm);
        }
        for (uint64_t k = 0; k < rounds && staged; ++k) {
            const uint64_t base = k * per;
            int so = 0, ro = 0;
            for (int d = 0; d < n; ++d) {
                uint64_t a = scount[d] > base ? scount[d] - base : 0, b = rcount[d] > base ? rcount[d] - base : 0;
                if (a > per) a = per;
                if (b > per) b = per;
                if (a) memcpy(stmp + so, (const uint8_t *)sendbuf + (sdisp[d] + base) * item, (size_t)(a * item));
                sc[d] = (int)(a * item);
                sd[d] = so;
                so += sc[d];
                rc[d] = (int)(b * item);
                rd[d] = ro;
                ro += rc[d];
            }
            MPI_Alltoallv(stmp, sc, sd, MPI_BYTE, rtmp, rc, rd, MPI_BYTE, c->comm);
            for (int d = 0; d < n; ++d)
                if (rc[d]) memcpy((uint8_t *)recvbuf + (rdisp[d] + base) * item, rtmp + rd[d], (size_t)rc[d]);
        }
        c->st.exchange_rounds += rounds;
    }
    MPI_Type_free(&type);
    free(sdisp);
    free(rdisp);
    free(sc);
    free(rc);
    free(sd);
    free(rd);
    free(stmp);
    free(rtmp);
    return s;
}

/* The vertex slice this rank read: global ids [v0, v0 + nv). */
typedef struct vslice {
    uint64_t v0, nv;
    float *pos; /* 3 nv */
    float *sc;  /* nv */
} vslice;

/* Collective: positions and scalars (4 floats per id, xyz s) of the sorted
 * unique global ids[0..n) from the ranks whose vertex slice holds them.
 * The caller agreed before; *out is this rank's (NULL on failure). */
static clvr_status fetch_vertices(load_ctx *c, const vslice *vs, const uint32_t *ids, uint64_t n, float **out)
{
    const int size = c->size;
    const uint64_t V = c->lay.num_vertices;
    uint64_t *scount = calloc((size_t)size, sizeof *scount), *rcount = calloc((size_t)size, sizeof *rcount);
    uint32_t *req = NULL;
    float *reply = NULL, *got = NULL;
    uint64_t nreq = 0;
    *out = NULL;
    clvr_status s = CLVR_OK;
    if (!scount || !rcount) s = clvr_error_set(&c->e, CLVR_ERR_NO_MEMORY, "%s: cannot allocate request counts", c->path);
    s = agree(c, s);
    if (s != CLVR_OK) goto done;
    for (uint64_t i = 0; i < n; ++i) ++scount[slice_owner(ids[i], V, size)];
    xchg_counts(c, scount, rcount);
    for (int d = 0; d < size; ++d) nreq += rcount[d];
    req = alloc_items(nreq, sizeof *req);
    got = alloc_items(n, 4 * sizeof *got);
    if (!req || !got)
        s = clvr_error_set(&c->e, CLVR_ERR_NO_MEMORY, "%s: cannot allocate %llu vertex requests", c->path,
                           (unsigned long long)(nreq + n));
    s = agree(c, s);
    if (s == CLVR_OK) s = xchg(c, ids, scount, req, rcount, sizeof *req);
    if (s != CLVR_OK) goto done;
    reply = alloc_items(nreq, 4 * sizeof *reply);
    if (!reply)
        s = clvr_error_set(&c->e, CLVR_ERR_NO_MEMORY, "%s: cannot allocate replies for %llu vertices", c->path,
                           (unsigned long long)nreq);
    for (uint64_t i = 0; i < nreq && s == CLVR_OK; ++i) {
        const uint64_t l = (uint64_t)req[i] - vs->v0; /* in this slice: slice_owner sent it here */
        memcpy(reply + 4 * i, vs->pos + 3 * l, 3 * sizeof(float));
        reply[4 * i + 3] = vs->sc[l];
    }
    free(req);
    req = NULL;
    s = agree(c, s);
    if (s == CLVR_OK) s = xchg(c, reply, rcount, got, scount, 4 * sizeof(float));
    if (s == CLVR_OK) {
        *out = got;
        got = NULL;
    }
done:
    free(scount);
    free(rcount);
    free(req);
    free(reply);
    free(got);
    return s;
}

/* ------------------------------------------------------------ reading */

static clvr_status read_vertex_slice(load_ctx *c, vslice *vs)
{
    const clvr_bin_layout *L = &c->lay;
    slice_of(L->num_vertices, c->rank, c->size, &vs->v0, &vs->nv);
    vs->pos = alloc_items(vs->nv, 3 * sizeof(float));
    vs->sc = alloc_items(vs->nv, sizeof(float));
    if (!vs->pos || !vs->sc)
        return clvr_error_set(&c->e, CLVR_ERR_NO_MEMORY, "%s: cannot allocate %llu vertices of this rank's slice",
                              c->path, (unsigned long long)vs->nv);
    clvr_status s = read_at(c, L->positions_offset + 12u * vs->v0, vs->pos, 12u * vs->nv, "positions");
    if (s != CLVR_OK) return s;
    const uint32_t nc = L->scalar_components;
    if (!L->has_scalar) {
        memset(vs->sc, 0, (size_t)vs->nv * sizeof(float));
    } else if (nc == 1) {
        s = read_at(c, L->scalar_offset + 4u * vs->v0, vs->sc, 4u * vs->nv, L->scalar_label);
    } else {
        float *buf = alloc_items(LOAD_TUPLE_CHUNK, (size_t)nc * sizeof(float));
        if (!buf) return clvr_error_set(&c->e, CLVR_ERR_NO_MEMORY, "%s: cannot allocate field scratch", c->path);
        for (uint64_t i0 = 0; i0 < vs->nv && s == CLVR_OK; i0 += LOAD_TUPLE_CHUNK) {
            uint64_t k = vs->nv - i0 < LOAD_TUPLE_CHUNK ? vs->nv - i0 : LOAD_TUPLE_CHUNK;
            s = read_at(c, L->scalar_offset + (vs->v0 + i0) * nc * 4u, buf, k * nc * 4u, L->scalar_label);
            for (uint64_t j = 0; j < k && s == CLVR_OK; ++j)
                vs->sc[i0 + j] = clvr_bin_tuple_value(buf + j * nc, nc, L->scalar_component);
        }
        free(buf);
    }
    if (s != CLVR_OK) return s;
    /* clvr_mesh_validate's checks and messages, with global vertex ids. */
    for (uint64_t i = 0; i < vs->nv; ++i) {
        const float *p = vs->pos + 3 * i;
        if (!isfinite(p[0]) || !isfinite(p[1]) || !isfinite(p[2]))
            return clvr_error_set(&c->e, CLVR_ERR_BAD_VALUE,
                                  "%s: vertex %llu has a non-finite coordinate (%g, %g, %g); fix or remove it",
                                  c->path, (unsigned long long)(vs->v0 + i), p[0], p[1], p[2]);
        if (!isfinite(vs->sc[i]))
            return clvr_error_set(&c->e, CLVR_ERR_BAD_VALUE,
                                  "%s: scalar '%s' at vertex %llu is %g; replace NaN/Inf values before rendering",
                                  c->path, L->scalar_label, (unsigned long long)(vs->v0 + i), vs->sc[i]);
    }
    return CLVR_OK;
}

/* This rank's element slice, per type: elements [first[t], first[t] +
 * count[t]) of type t, their indices in idx[t]. */
typedef struct eslice {
    uint64_t first[CLVR_CELL_TYPE_COUNT], count[CLVR_CELL_TYPE_COUNT];
    uint32_t *idx[CLVR_CELL_TYPE_COUNT];
} eslice;

static void eslice_free(eslice *es)
{
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) free(es->idx[t]);
    memset(es, 0, sizeof *es);
}

/* Checks the indices of es's type t (clvr_mesh_validate's message). */
static clvr_status check_indices(load_ctx *c, const eslice *es, uint32_t t)
{
    const uint32_t nv = clvr_cell_vertex_count(t);
    for (uint64_t j = 0; j < es->count[t] * nv; ++j)
        if ((uint64_t)es->idx[t][j] >= c->lay.num_vertices)
            return clvr_error_set(&c->e, CLVR_ERR_BAD_INDEX,
                                  "%s: %s[%llu] vertex %u is index %u but the mesh has %llu vertices", c->path,
                                  clvr_cell_type_name(t), (unsigned long long)(es->first[t] + j / nv),
                                  (unsigned)(j % nv), es->idx[t][j], (unsigned long long)c->lay.num_vertices);
    return CLVR_OK;
}

/* Elements [g0, g1) of the file (global ids across the four types), read
 * and validated into es (es->first[t]: the first one's index within its
 * type). */
static clvr_status read_elements(load_ctx *c, uint64_t g0, uint64_t g1, eslice *es)
{
    const clvr_bin_layout *L = &c->lay;
    clvr_status s = CLVR_OK;
    memset(es, 0, sizeof *es);
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT && s == CLVR_OK; ++t) {
        const uint64_t t0 = c->type_first[t], t1 = t0 + L->num_cells[t];
        const uint64_t a = g0 > t0 ? g0 : t0, b = g1 < t1 ? g1 : t1;
        const uint32_t nv = clvr_cell_vertex_count(t);
        es->first[t] = a > t0 ? a - t0 : 0;
        es->count[t] = b > a ? b - a : 0;
        es->idx[t] = alloc_items(es->count[t], nv * sizeof(uint32_t));
        if (!es->idx[t])
            return clvr_error_set(&c->e, CLVR_ERR_NO_MEMORY, "%s: cannot allocate %llu %s", c->path,
                                  (unsigned long long)es->count[t], clvr_cell_type_name(t));
        s = read_at(c, L->cells_offset[t] + es->first[t] * nv * 4u, es->idx[t], es->count[t] * nv * 4u,
                    clvr_cell_type_name(t));
        if (s == CLVR_OK) s = check_indices(c, es, t);
    }
    return s;
}

/* The sample's elements in [g0, g1): every one whose global id is a
 * multiple of stride, read one by one (at most 65536 in the whole job),
 * into es with first[t] unused; stride 1 (a small mesh) is the whole
 * range, read as read_elements reads it. */
static clvr_status read_sample(load_ctx *c, uint64_t g0, uint64_t g1, uint64_t stride, eslice *es)
{
    if (stride == 1) return read_elements(c, g0, g1, es);
    const clvr_bin_layout *L = &c->lay;
    clvr_status s = CLVR_OK;
    memset(es, 0, sizeof *es);
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT && s == CLVR_OK; ++t) {
        const uint64_t t0 = c->type_first[t], t1 = t0 + L->num_cells[t];
        const uint64_t a = g0 > t0 ? g0 : t0, b = g1 < t1 ? g1 : t1;
        const uint32_t nv = clvr_cell_vertex_count(t);
        uint64_t first = (a + stride - 1) / stride * stride, n = 0;
        if (first < b) n = (b - 1 - first) / stride + 1;
        es->idx[t] = alloc_items(n, nv * sizeof(uint32_t));
        if (!es->idx[t])
            return clvr_error_set(&c->e, CLVR_ERR_NO_MEMORY, "%s: cannot allocate the sample", c->path);
        es->count[t] = n;
        for (uint64_t k = 0; k < n && s == CLVR_OK; ++k)
            s = read_at(c, L->cells_offset[t] + (first + k * stride - t0) * nv * 4u, es->idx[t] + k * nv, nv * 4u,
                        clvr_cell_type_name(t));
        es->first[t] = first - t0;
        if (s == CLVR_OK) /* check each with its own element number */
            for (uint64_t k = 0; k < n && s == CLVR_OK; ++k) {
                eslice one;
                memset(&one, 0, sizeof one);
                one.first[t] = first + k * stride - t0;
                one.count[t] = 1;
                one.idx[t] = es->idx[t] + k * nv;
                s = check_indices(c, &one, t);
            }
    }
    return s;
}

/* Collective: the distinct vertices es uses, fetched from their slice
 * owners into *xyzs (4 floats each, by position in *ids), and es's indices
 * turned into positions in *ids (one lookup per corner). */
static clvr_status piece_vertices(load_ctx *c, const vslice *vs, eslice *es, uint32_t **ids, uint64_t *nids,
                                  float **xyzs)
{
    uint64_t n[CLVR_CELL_TYPE_COUNT];
    clvr_status s = CLVR_OK;
    *ids = NULL;
    *xyzs = NULL;
    *nids = 0;
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) n[t] = es->count[t] * clvr_cell_vertex_count(t);
    if (distinct_ids(es->idx, n, ids, nids))
        s = clvr_error_set(&c->e, CLVR_ERR_NO_MEMORY, "%s: cannot allocate vertex ids", c->path);
    id_index x;
    memset(&x, 0, sizeof x);
    if (s == CLVR_OK && id_index_build(&x, *ids, *nids))
        s = clvr_error_set(&c->e, CLVR_ERR_NO_MEMORY, "%s: cannot allocate the vertex id index", c->path);
    for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT && s == CLVR_OK; ++t)
        for (uint64_t q = 0; q < n[t]; ++q) es->idx[t][q] = (uint32_t)id_index_find(&x, es->idx[t][q]);
    free(x.start);
    s = agree(c, s);
    if (s == CLVR_OK) s = fetch_vertices(c, vs, *ids, *nids, xyzs);
    return s;
}

/* ------------------------------------------------------------ ranges */

/* Bounds and scalar range as clvr_mesh_update_ranges scans them: a value
 * replaces the running one only when strictly smaller (larger), so a tie
 * such as -0 and +0 keeps the first in file order. The operation is
 * declared non-commutative, which makes MPI combine the ranks' slices in
 * rank order, i.e. file order: the result is that of one scan. invec holds
 * the lower ranks' part. */
static void ranges_op(void *in, void *inout, int *len, MPI_Datatype *dt)
{
    (void)dt;
    const float *a = (const float *)in;
    float *b = (float *)inout;
    for (int i = 0; i < *len; ++i, a += 8, b += 8) {
        for (int k = 0; k < 3; ++k) {
            b[k] = b[k] < a[k] ? b[k] : a[k];
            b[3 + k] = b[3 + k] > a[3 + k] ? b[3 + k] : a[3 + k];
        }
        b[6] = b[6] < a[6] ? b[6] : a[6];
        b[7] = b[7] > a[7] ? b[7] : a[7];
    }
}

static void global_ranges(load_ctx *c, const vslice *vs, clvr_mpi_share *out)
{
    float r[8] = {FLT_MAX, FLT_MAX, FLT_MAX, -FLT_MAX, -FLT_MAX, -FLT_MAX, FLT_MAX, -FLT_MAX}, g[8];
    for (uint64_t i = 0; i < vs->nv; ++i) {
        for (int k = 0; k < 3; ++k) {
            float v = vs->pos[3 * i + k];
            r[k] = v < r[k] ? v : r[k];
            r[3 + k] = v > r[3 + k] ? v : r[3 + k];
        }
        r[6] = vs->sc[i] < r[6] ? vs->sc[i] : r[6];
        r[7] = vs->sc[i] > r[7] ? vs->sc[i] : r[7];
    }
    MPI_Datatype t;
    MPI_Op op;
    MPI_Type_contiguous(8, MPI_FLOAT, &t);
    MPI_Type_commit(&t);
    MPI_Op_create(ranges_op, 0, &op);
    MPI_Allreduce(r, g, 1, t, op, c->comm);
    MPI_Op_free(&op);
    MPI_Type_free(&t);
    if (c->lay.num_vertices == 0) memset(g, 0, sizeof g); /* as clvr_mesh_update_ranges */
    memcpy(out->bounds_lo, g, 3 * sizeof(float));
    memcpy(out->bounds_hi, g + 3, 3 * sizeof(float));
    out->scalar_min = g[6];
    out->scalar_max = g[7];
}

/* ------------------------------------------------------------ elements */

/* Vertex box and centroid of one element from its vertices' positions
 * (xyzs records, 4 floats each, gathered in vertex order). The centroid is
 * clamped into the box: the float mean of equal coordinates can round one
 * ulp outside it, and the owner region must be one the box overlaps. Both
 * ends compute it from the same bits, so they agree. */
static void element_geometry(const float *const *v, uint32_t nv, float lo[3], float hi[3], float cen[3])
{
    for (int k = 0; k < 3; ++k) {
        float a = v[0][k], b = v[0][k], sum = v[0][k];
        for (uint32_t j = 1; j < nv; ++j) {
            float x = v[j][k];
            a = x < a ? x : a;
            b = x > b ? x : b;
            sum += x;
        }
        float m = sum / (float)nv;
        lo[k] = a;
        hi[k] = b;
        cen[k] = m < a ? a : (m > b ? b : m);
    }
}

/* ------------------------------------------------------------ the load */

clvr_status clvr_mpi_load_share_bin_ex(MPI_Comm comm, const char *path, const clvr_load_options *lo,
                                       uint64_t chunk_bytes, clvr_mpi_share *out, clvr_mpi_load_stats *stats,
                                       clvr_error *err)
{
    load_ctx c;
    memset(&c, 0, sizeof c);
    memset(out, 0, sizeof *out);
    if (stats) memset(stats, 0, sizeof *stats);
    c.comm = comm;
    c.path = path;
    c.fd = -1;
    c.staged = chunk_bytes != 0;
    c.chunk_bytes = chunk_bytes ? (chunk_bytes < LOAD_CHUNK_MAX ? chunk_bytes : LOAD_CHUNK_MAX) : LOAD_CHUNK_DEFAULT;
    MPI_Comm_rank(comm, &c.rank);
    MPI_Comm_size(comm, &c.size);
    const int rank = c.rank, size = c.size;
    vslice vs = {0, 0, NULL, NULL};
    eslice es;
    memset(&es, 0, sizeof es);
    uint32_t *ids = NULL, *tmp = NULL, *rec = NULL, *recv = NULL;
    float *xyzs = NULL, *sample = NULL, *regions = NULL;
    uint64_t *scount = NULL, *rcount = NULL;
    int *gcount = NULL, *gdisp = NULL;
    uint64_t nids = 0, nrecv = 0;
    clvr_status s = CLVR_OK;

    /* 1. Header, slices, validation. */
    c.fd = open(path, O_RDONLY);
    if (c.fd < 0) s = clvr_error_set(&c.e, CLVR_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
    if (s == CLVR_OK) s = clvr_mesh_bin_layout(c.fd, path, lo ? lo->scalar_name : NULL, &c.lay, &c.e);
    if (s == CLVR_OK) c.st.bytes_read += 256u; /* the header (and a v2 field table, uncounted: small) */
    if (s == CLVR_OK && c.lay.has_scalar && c.lay.scalar_association == CLVR_FIELD_CELL)
        s = clvr_error_set(&c.e, CLVR_ERR_BAD_FIELD,
                           "%s: field '%s' is cell data, which MPI mode cannot average onto vertices (each vertex "
                           "needs the elements of every rank); pick a point field with --scalar point:NAME, or "
                           "render this field with one process",
                           path, c.lay.scalar_label);
    if (s == CLVR_OK) {
        for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) {
            c.type_first[t] = c.num_elements;
            c.num_elements += c.lay.num_cells[t]; /* the layout checked the sizes: no overflow */
        }
        if (c.num_elements == 0)
            s = clvr_error_set(&c.e, CLVR_ERR_EMPTY,
                               "%s: the mesh has no elements (0 tets, pyramids, wedges, hexes)", path);
    }
    if (s == CLVR_OK) s = read_vertex_slice(&c, &vs);
    c.st.slice_vertices = vs.nv;
    uint64_t e0 = 0, ne = 0;
    slice_of(c.num_elements, rank, size, &e0, &ne);
    c.st.slice_elements = ne;
    {
        uint64_t e1 = e0 + ne, bytes = 256u + vs.nv * 12u;
        if (c.lay.has_scalar) bytes += vs.nv * 4u * c.lay.scalar_components;
        for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) {
            const uint64_t t0 = c.type_first[t], t1 = t0 + c.lay.num_cells[t];
            const uint64_t a = e0 > t0 ? e0 : t0, b = e1 < t1 ? e1 : t1;
            if (b > a) bytes += (b - a) * clvr_cell_vertex_count(t) * 4u;
        }
        c.st.slice_bytes = bytes;
    }

    /* 2. The sample's elements of this slice (validated). */
    const uint64_t stride = (c.num_elements + LOAD_SAMPLE_MAX - 1) / LOAD_SAMPLE_MAX;
    if (s == CLVR_OK) s = read_sample(&c, e0, e0 + ne, stride, &es);
    s = agree(&c, s);
    if (s != CLVR_OK) goto done;

    /* 3. Global bounds and scalar range. */
    global_ranges(&c, &vs, out);
    out->global_vertices = c.lay.num_vertices;
    out->global_elements = c.num_elements;

    /* 4. Regions from the sample's centroids, gathered in rank order (file
     * order): the same sample, and so the same boxes, on every rank. */
    s = piece_vertices(&c, &vs, &es, &ids, &nids, &xyzs);
    if (s != CLVR_OK) goto done;
    {
        uint64_t nmine = 0;
        for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) nmine += es.count[t];
        sample = alloc_items(LOAD_SAMPLE_MAX + 1u, 3 * sizeof(float));
        regions = alloc_items((uint64_t)size, 6 * sizeof(float));
        gcount = calloc((size_t)size, sizeof *gcount);
        gdisp = calloc((size_t)size, sizeof *gdisp);
        float *mine = alloc_items(nmine, 3 * sizeof(float));
        if (!sample || !regions || !gcount || !gdisp || !mine)
            s = clvr_error_set(&c.e, CLVR_ERR_NO_MEMORY, "%s: cannot allocate the centroid sample", path);
        s = agree(&c, s);
        if (s != CLVR_OK) {
            free(mine);
            goto done;
        }
        uint64_t m = 0;
        for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) {
            const uint32_t nv = clvr_cell_vertex_count(t);
            for (uint64_t j = 0; j < es.count[t]; ++j) {
                const float *v[CLVR_CELL_MAX_VERTS];
                float blo[3], bhi[3];
                for (uint32_t q = 0; q < nv; ++q) v[q] = xyzs + 4 * (uint64_t)es.idx[t][j * nv + q];
                element_geometry(v, nv, blo, bhi, mine + 3 * m++);
            }
        }
        int n3 = (int)(3 * nmine); /* at most 3 * 65536 in all: int counts suffice */
        MPI_Allgather(&n3, 1, MPI_INT, gcount, 1, MPI_INT, comm);
        uint64_t total = 0;
        for (int r = 0; r < size; ++r) {
            gdisp[r] = (int)total;
            total += (uint64_t)gcount[r];
        }
        MPI_Allgatherv(mine, n3, MPI_FLOAT, sample, gcount, gdisp, MPI_FLOAT, comm);
        free(mine);
        c.st.sample = total / 3;
        s = clvr_mpi_regions(sample, total / 3, out->bounds_lo, out->bounds_hi, (uint32_t)size, regions, &c.e);
        s = agree(&c, s);
        if (s != CLVR_OK) goto done;
        memcpy(out->region_lo, regions + 6 * rank, 3 * sizeof(float));
        memcpy(out->region_hi, regions + 6 * rank + 3, 3 * sizeof(float));
    }
    eslice_free(&es);
    free(ids);
    free(xyzs);
    ids = NULL;
    xyzs = NULL;

    /* 5. Every element to every rank whose region its vertex box overlaps,
     * streamed: the slice is read in pieces of about chunk / (36 N)
     * elements (a record is at most 9 words), the same number of rounds on
     * every rank. Pass 0 fetches each piece's vertices, finds each
     * element's destinations and keeps them compactly (the first in dest0,
     * one word per element; the others, ghosts, as (element, rank) pairs)
     * and counts them per destination and type, so that each receiver
     * allocates its index arrays once and places every sender's elements
     * at their file-order position. Pass 1 reads the pieces again and
     * sends the records (type, global vertex ids as in the file) without
     * fetching anything. No rank holds its whole slice's indices, nor
     * anything of the size of its share besides the share. */
    uint64_t piece = c.chunk_bytes / (36u * (uint64_t)size);
    if (piece == 0) piece = 1;
    uint64_t rounds = 0, mine_rounds = (ne + piece - 1) / piece;
    MPI_Allreduce(&mine_rounds, &rounds, 1, MPI_UINT64_T, MPI_MAX, comm);
    const size_t nt = CLVR_CELL_TYPE_COUNT;
    uint64_t *tcount = calloc((size_t)size * nt, sizeof *tcount), *rtcount = calloc((size_t)size * nt, sizeof *rtcount);
    uint64_t *cursor = calloc((size_t)size * nt, sizeof *cursor);
    scount = calloc((size_t)size, sizeof *scount);
    rcount = calloc((size_t)size, sizeof *rcount);
    uint64_t *fill = calloc((size_t)size, sizeof *fill);
    uint32_t *dest0 = alloc_items(ne, sizeof *dest0);
    uint64_t *extra = NULL, nextra = 0, capextra = 0; /* pairs: slice element, rank */
    if (!tcount || !rtcount || !cursor || !scount || !rcount || !fill || !dest0)
        s = clvr_error_set(&c.e, CLVR_ERR_NO_MEMORY, "%s: cannot allocate counts", path);
    s = agree(&c, s);
    for (int pass = 0; pass < 2 && s == CLVR_OK; ++pass) {
        uint64_t xi = 0; /* pass 1: next extra pair */
        for (uint64_t k = 0; k < rounds && s == CLVR_OK; ++k) {
            const uint64_t g0 = e0 + (k * piece < ne ? k * piece : ne);
            const uint64_t g1 = e0 + ((k + 1) * piece < ne ? (k + 1) * piece : ne);
            s = read_elements(&c, g0, g1, &es);
            if (pass == 0) {
                s = agree(&c, s);
                if (s == CLVR_OK) s = piece_vertices(&c, &vs, &es, &ids, &nids, &xyzs);
                if (s != CLVR_OK) break;
                uint64_t i = g0 - e0; /* slice element */
                for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT && s == CLVR_OK; ++t) {
                    const uint32_t nv = clvr_cell_vertex_count(t);
                    for (uint64_t j = 0; j < es.count[t] && s == CLVR_OK; ++j, ++i) {
                        const uint32_t *e = es.idx[t] + j * nv;
                        const float *v[CLVR_CELL_MAX_VERTS];
                        float blo[3], bhi[3], cen[3];
                        for (uint32_t q = 0; q < nv; ++q) v[q] = xyzs + 4 * (uint64_t)e[q];
                        element_geometry(v, nv, blo, bhi, cen);
                        dest0[i] = UINT32_MAX;
                        for (int d = 0; d < size; ++d) {
                            if (!clvr_mpi_boxes_overlap(blo, bhi, regions + 6 * d, regions + 6 * d + 3)) continue;
                            ++tcount[(size_t)d * nt + t];
                            if (dest0[i] == UINT32_MAX) {
                                dest0[i] = (uint32_t)d;
                                continue;
                            }
                            if (nextra == capextra) {
                                uint64_t ncap = capextra ? 2 * capextra : 4096;
                                uint64_t *nx = ncap <= SIZE_MAX / (2 * sizeof *nx)
                                                   ? realloc(extra, (size_t)ncap * 2 * sizeof *nx) : NULL;
                                if (!nx) {
                                    s = clvr_error_set(&c.e, CLVR_ERR_NO_MEMORY, "%s: cannot allocate ghost lists",
                                                       path);
                                    break;
                                }
                                extra = nx;
                                capextra = ncap;
                            }
                            extra[2 * nextra] = i;
                            extra[2 * nextra + 1] = (uint64_t)d;
                            ++nextra;
                        }
                    }
                }
                eslice_free(&es);
                free(ids);
                free(xyzs);
                ids = NULL;
                xyzs = NULL;
                s = agree(&c, s);
                continue;
            }
            /* Pass 1: records from the file's indices and the destinations
             * found in pass 0; count, then fill. */
            memset(scount, 0, (size_t)size * sizeof *scount);
            const uint64_t xi0 = xi;
            for (int fillpass = 0; fillpass < 2 && s == CLVR_OK; ++fillpass) {
                uint64_t i = g0 - e0;
                xi = xi0;
                for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) {
                    const uint32_t nv = clvr_cell_vertex_count(t);
                    for (uint64_t j = 0; j < es.count[t]; ++j, ++i) {
                        const uint32_t *e = es.idx[t] + j * nv;
                        for (int first = 1; first || (xi < nextra && extra[2 * xi] == i); first = 0) {
                            uint32_t d;
                            if (first) d = dest0[i];
                            else d = (uint32_t)extra[2 * xi++ + 1];
                            if (d == UINT32_MAX) continue;
                            if (fillpass == 0) {
                                scount[d] += REC_HEAD + nv;
                                continue;
                            }
                            uint32_t *r = rec + fill[d];
                            r[0] = t;
                            memcpy(r + REC_HEAD, e, nv * sizeof *e);
                            fill[d] += REC_HEAD + nv;
                        }
                    }
                }
                if (fillpass == 0) {
                    uint64_t total = 0;
                    for (int d = 0; d < size; ++d) {
                        fill[d] = total;
                        total += scount[d];
                    }
                    rec = alloc_items(total, sizeof *rec);
                    if (!rec)
                        s = clvr_error_set(&c.e, CLVR_ERR_NO_MEMORY,
                                           "%s: cannot allocate %llu words of elements to send", path,
                                           (unsigned long long)total);
                }
            }
            eslice_free(&es);
            s = agree(&c, s);
            if (s != CLVR_OK) break;
            xchg_counts(&c, scount, rcount);
            nrecv = 0;
            for (int d = 0; d < size; ++d) nrecv += rcount[d];
            recv = alloc_items(nrecv, sizeof *recv);
            if (!recv)
                s = clvr_error_set(&c.e, CLVR_ERR_NO_MEMORY, "%s: cannot allocate %llu words of received elements",
                                   path, (unsigned long long)nrecv);
            s = agree(&c, s);
            if (s == CLVR_OK) s = xchg(&c, rec, scount, recv, rcount, sizeof *rec);
            free(rec);
            rec = NULL;
            /* Each sender's records in its file order, at its place. */
            clvr_mesh *m = &out->mesh;
            uint64_t w = 0;
            for (int src = 0; src < size && s == CLVR_OK; ++src) {
                const uint64_t end = w + rcount[src];
                while (w < end) {
                    const uint32_t t = recv[w], nv = clvr_cell_vertex_count(t);
                    uint64_t *cur = &cursor[(size_t)src * nt + t];
                    memcpy(m->indices[t] + *cur * nv, recv + w + REC_HEAD, nv * sizeof(uint32_t));
                    ++*cur;
                    w += REC_HEAD + nv;
                }
            }
            free(recv);
            recv = NULL;
        }
        if (pass == 0 && s == CLVR_OK) {
            /* Each receiver: how many elements of each type each sender
             * has for it; the index arrays, and where each sender's go. */
            MPI_Alltoall(tcount, (int)nt, MPI_UINT64_T, rtcount, (int)nt, MPI_UINT64_T, comm);
            uint64_t ncells[CLVR_CELL_TYPE_COUNT] = {0};
            for (int src = 0; src < size; ++src)
                for (size_t t = 0; t < nt; ++t) {
                    cursor[(size_t)src * nt + t] = ncells[t];
                    ncells[t] += rtcount[(size_t)src * nt + t];
                }
            s = clvr_mesh_alloc(&out->mesh, 0, ncells, &c.e);
            s = agree(&c, s);
        }
    }
    free(dest0);
    free(extra);
    free(tcount);
    free(rtcount);
    free(cursor);
    free(fill);
    if (s != CLVR_OK) goto done;

    /* 6. The share: its index arrays hold global ids, each type in file
     * order. The distinct ids, sorted, become the local numbering; their
     * vertices are fetched and the indices renumbered in place. */
    {
        clvr_mesh *m = &out->mesh;
        const uint64_t nelem = clvr_mesh_num_elements(m);
        if (s == CLVR_OK) {
            uint64_t n[CLVR_CELL_TYPE_COUNT];
            for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) n[t] = clvr_mesh_num_indices(m, t);
            if (distinct_ids(m->indices, n, &ids, &nids))
                s = clvr_error_set(&c.e, CLVR_ERR_NO_MEMORY, "%s: cannot allocate the vertex ids of the share", path);
        }
        s = agree(&c, s);
        if (s == CLVR_OK) s = fetch_vertices(&c, &vs, ids, nids, &xyzs);
        if (s == CLVR_OK) {
            free(m->positions);
            free(m->scalars);
            m->num_vertices = nids;
            m->positions = alloc_items(nids, 3 * sizeof(float));
            m->scalars = alloc_items(nids, sizeof(float));
            if (!m->positions || !m->scalars)
                s = clvr_error_set(&c.e, CLVR_ERR_NO_MEMORY, "%s: cannot allocate the share's %llu vertices", path,
                                   (unsigned long long)nids);
        }
        s = agree(&c, s);
        if (s != CLVR_OK) goto done;
        for (uint64_t i = 0; i < nids; ++i) {
            memcpy(m->positions + 3 * i, xyzs + 4 * i, 3 * sizeof(float));
            m->scalars[i] = xyzs[4 * i + 3];
        }
        uint64_t owned = 0, elem = 0;
        id_index x;
        memset(&x, 0, sizeof x);
        out->owned = malloc(nelem ? nelem : 1);
        if (!out->owned)
            s = clvr_error_set(&c.e, CLVR_ERR_NO_MEMORY, "%s: cannot allocate the share's ownership flags", path);
        else if (id_index_build(&x, ids, nids))
            s = clvr_error_set(&c.e, CLVR_ERR_NO_MEMORY, "%s: cannot allocate the vertex id index", path);
        s = agree(&c, s);
        if (s != CLVR_OK) goto done;
        for (uint32_t t = 0; t < CLVR_CELL_TYPE_COUNT; ++t) {
            const uint32_t nv = clvr_cell_vertex_count(t);
            for (uint64_t j = 0; j < m->num_cells[t]; ++j) {
                uint32_t *e = m->indices[t] + j * nv;
                const float *v[CLVR_CELL_MAX_VERTS];
                for (uint32_t q = 0; q < nv; ++q) {
                    e[q] = (uint32_t)id_index_find(&x, e[q]);
                    v[q] = xyzs + 4 * (uint64_t)e[q];
                }
                float blo[3], bhi[3], cen[3];
                element_geometry(v, nv, blo, bhi, cen);
                const int mine = clvr_mpi_region_of(regions, (uint32_t)size, cen) == (uint32_t)rank;
                out->owned[elem++] = (uint8_t)mine;
                owned += (uint64_t)mine;
            }
        }
        free(x.start);
        clvr_mesh_set_scalar_name(m, c.lay.scalar_label, CLVR_SCALAR_NAME_MAX);
        clvr_mesh_update_ranges(m);
        out->owned_elements = owned;
        c.st.share_elements = nelem;
        c.st.ghost_elements = nelem - owned;
    }

done:
    if (c.fd >= 0) close(c.fd);
    free(vs.pos);
    free(vs.sc);
    eslice_free(&es);
    free(ids);
    free(tmp);
    free(rec);
    free(recv);
    free(xyzs);
    free(sample);
    free(regions);
    free(scount);
    free(rcount);
    free(gcount);
    free(gdisp);
    if (stats) *stats = c.st;
    if (s != CLVR_OK) {
        clvr_mpi_share_free(out);
        if (err) *err = c.e;
        return s;
    }
    return CLVR_OK;
}

clvr_status clvr_mpi_load_share_bin(MPI_Comm comm, const char *path, const clvr_load_options *lo,
                                    clvr_mpi_share *out, clvr_error *err)
{
    return clvr_mpi_load_share_bin_ex(comm, path, lo, 0, out, NULL, err);
}
