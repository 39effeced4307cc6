/* mesh_io.c: clvr_mesh_load picks a reader by the file's first bytes, then
 * by its extension; the .umesh and .vtk file loaders map the file and call
 * the memory parsers (.bin has its own loader that reads straight into the
 * mesh arrays). */
#include "mesh_io.h"

#include <errno.h>
#include <fcntl.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <strings.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

typedef clvr_status (*parse_fn)(const void *data, size_t size, const char *name, const clvr_load_options *opt,
                                clvr_mesh *out, clvr_error *err);

/* Opens path as a regular file; directories and devices are refused with a
 * message saying so. */
static clvr_status open_regular(const char *path, int *fd_out, uint64_t *size_out, clvr_error *err)
{
    struct stat st;
    *fd_out = -1;
    int fd = open(path, O_RDONLY);
    if (fd < 0) return clvr_error_set(err, CLVR_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
    if (fstat(fd, &st) != 0) {
        int e = errno;
        close(fd);
        return clvr_error_set(err, CLVR_ERR_IO, "%s: cannot stat: %s", path, strerror(e));
    }
    if (!S_ISREG(st.st_mode)) {
        close(fd);
        return clvr_error_set(err, CLVR_ERR_IO, "%s: is %s, not a mesh file", path,
                              S_ISDIR(st.st_mode) ? "a directory" : "not a regular file");
    }
    *fd_out = fd;
    *size_out = (uint64_t)st.st_size;
    return CLVR_OK;
}

/* Maps the whole file read-only (no heap copy of multi-GB inputs) and runs
 * the parser on it. */
static clvr_status load_mapped(const char *path, parse_fn parse, const clvr_load_options *opt, clvr_mesh *out,
                               clvr_error *err)
{
    int fd;
    uint64_t size;
    memset(out, 0, sizeof *out);
    clvr_status s = open_regular(path, &fd, &size, err);
    if (s != CLVR_OK) return s;
    if (size > (uint64_t)SIZE_MAX) {
        close(fd);
        return clvr_error_set(err, CLVR_ERR_OVERFLOW, "%s: %llu bytes do not fit the address space", path,
                              (unsigned long long)size);
    }
    if (size == 0) {
        close(fd);
        static const char empty[1] = {0};
        return parse(empty, 0, path, opt, out, err);
    }
    void *p = mmap(NULL, (size_t)size, PROT_READ, MAP_PRIVATE, fd, 0);
    int e = errno;
    close(fd);
    if (p == MAP_FAILED) return clvr_error_set(err, CLVR_ERR_IO, "%s: cannot map the file: %s", path, strerror(e));
    s = parse(p, (size_t)size, path, opt, out, err);
    munmap(p, (size_t)size);
    return s;
}

clvr_status clvr_mesh_load_umesh(const char *path, const clvr_load_options *opt, clvr_mesh *out, clvr_error *err)
{
    return load_mapped(path, clvr_mesh_parse_umesh, opt, out, err);
}

clvr_status clvr_mesh_load_vtk(const char *path, const clvr_load_options *opt, clvr_mesh *out, clvr_error *err)
{
    return load_mapped(path, clvr_mesh_parse_vtk, opt, out, err);
}

static int has_ext(const char *path, const char *ext)
{
    size_t n = strlen(path), e = strlen(ext);
    return n > e && strcasecmp(path + n - e, ext) == 0;
}

/* Formats tools/clvr-convert reads and clvr does not: each gets a message
 * with the command that converts it. Keep in step with CONVERTER_EXT in
 * tools/clvr-convert (tests/test_convert.py checks every one). */
static const struct {
    const char *ext, *what;
} converted_formats[] = {
    {".vts", "VTK XML (.vts)"},        {".vtr", "VTK XML (.vtr)"},
    {".vti", "VTK XML (.vti)"},         {".vtm", "VTK XML (.vtm)"},        {".vtmb", "VTK XML (.vtmb)"},
    {".vtp", "VTK XML (.vtp)"},         {".vthb", "VTK XML (.vthb)"},      {".vtpc", "VTK XML (.vtpc)"},
    {".pvtu", "parallel VTK XML (.pvtu)"}, {".pvts", "parallel VTK XML (.pvts)"},
    {".pvtr", "parallel VTK XML (.pvtr)"}, {".pvti", "parallel VTK XML (.pvti)"},
    {".ex2", "Exodus II (.ex2)"},       {".exo", "Exodus II (.exo)"},      {".e", "Exodus II (.e)"},
    {".exii", "Exodus II (.exii)"},     {".gen", "Exodus II (.gen)"},
    {".g", "Exodus II or PLOT3D (.g)"}, {".cgns", "CGNS (.cgns)"},         {".inp", "AVS UCD (.inp)"},
    {".xyz", "PLOT3D (.xyz)"},          {".x", "PLOT3D (.x)"},             {".p3d", "PLOT3D (.p3d)"},
    {".grd", "PLOT3D (.grd)"},          {".pvd", "ParaView time series (.pvd)"},
};

clvr_status clvr_mesh_load(const char *path, const clvr_load_options *opt, clvr_mesh *out, clvr_error *err)
{
    int fd;
    uint64_t size;
    uint8_t head[32] = {0};
    size_t have = 0;
    memset(out, 0, sizeof *out);
    clvr_status s = open_regular(path, &fd, &size, err);
    if (s != CLVR_OK) return s;
    while (have < sizeof head) {
        ssize_t got = read(fd, head + have, sizeof head - have);
        if (got < 0 && errno == EINTR) continue;
        if (got < 0) {
            int e = errno;
            close(fd);
            return clvr_error_set(err, CLVR_ERR_IO, "%s: cannot read: %s", path, strerror(e));
        }
        if (got == 0) break;
        have += (size_t)got;
    }
    close(fd);

    /* Content first: a file renamed to the wrong extension still loads. */
    if (have >= 8 && memcmp(head, "CLVRMESH", 8) == 0) return clvr_mesh_load_bin(path, opt, out, err);
    if (have >= 8) {
        uint64_t magic = 0;
        for (int i = 7; i >= 0; --i) magic = magic << 8 | head[i];
        if (magic >= 0x234235566ull && magic <= 0x234235569ull) return clvr_mesh_load_umesh(path, opt, out, err);
    }
    if (have >= 14 && memcmp(head, "# vtk DataFile", 14) == 0) return clvr_mesh_load_vtk(path, opt, out, err);

    if (has_ext(path, ".bin")) return clvr_mesh_load_bin(path, opt, out, err);
    if (has_ext(path, ".umesh")) return clvr_mesh_load_umesh(path, opt, out, err);
    if (has_ext(path, ".vtk")) return clvr_mesh_load_vtk(path, opt, out, err);
    if (has_ext(path, ".vtu"))
        return clvr_error_set(err, CLVR_ERR_FORMAT,
                              "%s: VTK XML (.vtu) is not read directly; convert it with "
                              "tools/clvr-convert %s OUT.bin (or save it as legacy .vtk) and load that",
                              path, path);
    for (size_t i = 0; i < sizeof converted_formats / sizeof converted_formats[0]; ++i)
        if (has_ext(path, converted_formats[i].ext))
            return clvr_error_set(err, CLVR_ERR_FORMAT,
                                  "%s: unknown mesh format (%llu bytes): clvr reads .bin, .umesh and legacy .vtk; "
                                  "convert this %s file with tools/clvr-convert %s OUT.bin and load that",
                                  path, (unsigned long long)size, converted_formats[i].what, path);
    return clvr_error_set(err, CLVR_ERR_FORMAT,
                          "%s: unknown mesh format (%llu bytes); clvr reads clvr .bin, .umesh and legacy VTK .vtk "
                          "unstructured grids; tools/clvr-convert converts what VTK reads (.vtu, Exodus, CGNS, "
                          "PLOT3D, AVS .inp, .pvd time series, ...)",
                          path, (unsigned long long)size);
}
