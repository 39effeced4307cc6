// bench_vtk_locate.cpp: VTK's vtkStaticCellLocator::FindCell on the mesh and
// query points that `bench_locate_embree --dump FILE` wrote (same mesh, same
// points as the clvr / Embree comparison). Times BuildLocator and the
// FindCell loops only, on T std::threads over query chunks (FindCell with a
// per-thread vtkGenericCell is thread-safe after BuildLocator). Built only
// when CMake finds VTK 9 (Debian: libvtk9-dev); the executable is
// vtk_locate, not bench_*, since it needs the dump (run-all.sh skips it).
//
//   vtk_locate FILE [--threads T]
// prints `vtk_queries_per_s: Q`, `vtk_build_s: S`, `vtk_found: F` lines.
#include <vtkCellArray.h>
#include <vtkCellType.h>
#include <vtkGenericCell.h>
#include <vtkIdList.h>
#include <vtkNew.h>
#include <vtkPoints.h>
#include <vtkSmartPointer.h>
#include <vtkStaticCellLocator.h>
#include <vtkUnsignedCharArray.h>
#include <vtkUnstructuredGrid.h>
#include <vtkVersionMacros.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

static double now_s()
{
    return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

static double load1()
{
    double l = -1.0;
    if (FILE *f = std::fopen("/proc/loadavg", "r")) {
        if (std::fscanf(f, "%lf", &l) != 1) l = -1.0;
        std::fclose(f);
    }
    return l;
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        std::fprintf(stderr, "usage: %s FILE [--threads T]\n", argv[0]);
        return 2;
    }
    int threads = 2;
    for (int i = 2; i < argc; ++i)
        if (!std::strcmp(argv[i], "--threads") && i + 1 < argc) threads = std::max(1, std::atoi(argv[++i]));
    FILE *f = std::fopen(argv[1], "rb");
    char magic[8];
    uint64_t h[6];
    if (!f || std::fread(magic, 1, 8, f) != 8 || std::memcmp(magic, "CLVRLOC1", 8) != 0 || std::fread(h, sizeof h, 1, f) != 1) {
        std::fprintf(stderr, "vtk_locate: %s is not a bench_locate_embree --dump file\n", argv[1]);
        return 1;
    }
    const uint64_t nv = h[0], nq = h[5];
    const uint64_t ncell[4] = {h[1], h[2], h[3], h[4]};
    const int vcount[4] = {4, 5, 6, 8};
    const int vtype[4] = {VTK_TETRA, VTK_PYRAMID, VTK_WEDGE, VTK_HEXAHEDRON};
    std::vector<float> pos(3 * nv), sc(nv), pts(3 * nq);
    bool ok = std::fread(pos.data(), 12, nv, f) == nv && std::fread(sc.data(), 4, nv, f) == nv;
    std::vector<std::vector<uint32_t>> idx(4);
    for (int t = 0; t < 4 && ok; ++t) {
        idx[t].resize(ncell[t] * vcount[t]);
        ok = std::fread(idx[t].data(), 4, idx[t].size(), f) == idx[t].size();
    }
    ok = ok && std::fread(pts.data(), 12, nq, f) == nq;
    std::fclose(f);
    if (!ok) {
        std::fprintf(stderr, "vtk_locate: %s is truncated\n", argv[1]);
        return 1;
    }
    vtkNew<vtkPoints> points;
    points->SetDataTypeToFloat();
    points->SetNumberOfPoints((vtkIdType)nv);
    for (uint64_t i = 0; i < nv; ++i) points->SetPoint((vtkIdType)i, pos[3 * i], pos[3 * i + 1], pos[3 * i + 2]);
    vtkNew<vtkUnstructuredGrid> grid;
    grid->SetPoints(points);
    uint64_t ne = 0;
    for (int t = 0; t < 4; ++t) ne += ncell[t];
    grid->Allocate((vtkIdType)ne);
    vtkIdType ids[8];
    for (int t = 0; t < 4; ++t)
        for (uint64_t e = 0; e < ncell[t]; ++e) {
            for (int k = 0; k < vcount[t]; ++k) ids[k] = idx[t][e * vcount[t] + k];
            grid->InsertNextCell(vtype[t], vcount[t], ids);
        }
    vtkNew<vtkStaticCellLocator> loc;
    loc->SetDataSet(grid);
    double t0 = now_s();
    loc->BuildLocator();
    const double build = now_s() - t0;
    std::vector<int> found(threads, 0);
    auto run = [&](int th) {
        vtkNew<vtkGenericCell> cell;
        double pc[3], w[8];
        const uint64_t b = nq * th / threads, e = nq * (th + 1) / threads;
        int n = 0;
        for (uint64_t i = b; i < e; ++i) {
            const double x[3] = {pts[3 * i], pts[3 * i + 1], pts[3 * i + 2]};
            n += loc->FindCell(const_cast<double *>(x), 0.0, cell.GetPointer(), pc, w) >= 0;
        }
        found[th] = n;
    };
    run(0); // warm-up (first-touch of the locator)
    std::vector<double> times, loads;
    for (int r = 0; r < 5; ++r) {
        t0 = now_s();
        std::vector<std::thread> pool;
        for (int th = 0; th < threads; ++th) pool.emplace_back(run, th);
        for (auto &p : pool) p.join();
        times.push_back(now_s() - t0);
        loads.push_back(load1());
    }
    std::sort(times.begin(), times.end());
    std::sort(loads.begin(), loads.end());
    int nf = 0;
    for (int v : found) nf += v;
    std::printf("# vtk_locate: vtkStaticCellLocator (VTK %s), %llu cells, %llu points, %d threads\n",
                VTK_VERSION, (unsigned long long)ne, (unsigned long long)nq, threads);
    std::printf("vtk_queries_per_s: %.6g\n", nq / times[2]);
    std::printf("vtk_build_s: %.4f\n", build);
    std::printf("vtk_found: %.5f\n", nq ? (double)nf / nq : 0.0);
    std::printf("vtk_load: %.2f\n", loads[2]);
    return 0;
}
