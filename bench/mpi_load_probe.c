/* mpi_load_probe.c: the program behind bench/mpi-load.sh (not a bench_* of
 * bench/run-all.sh: it runs under mpirun and takes a mesh file). One line per rank: bytes of
 * the file regions read and bytes read (re-reads counted),
 * load time, peak RSS, the mesh or share arrays (MiB) and the share's elements (owned, ghosts), from
 * clvr_mpi_load_share_bin; with --single, one process's clvr_mesh_load of
 * the same file instead (the baseline). */
#include <mpi.h>
#include <stdio.h>
#include <string.h>
#include <sys/resource.h>

#include "clock.h"
#include "mesh_io.h"
#include "mpi_load.h"

static double peak_rss_mib(void)
{
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    return (double)ru.ru_maxrss / 1024.0; /* Linux: KiB */
}

static double cpu_s(void)
{
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    return (double)ru.ru_utime.tv_sec + 1e-6 * ru.ru_utime.tv_usec + (double)ru.ru_stime.tv_sec +
           1e-6 * ru.ru_stime.tv_usec;
}

int main(int argc, char **argv)
{
    MPI_Init(&argc, &argv);
    int rank, size, single = argc == 3 && !strcmp(argv[2], "--single");
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &size);
    if (argc < 2) {
        if (rank == 0) fprintf(stderr, "usage: mpi_load_probe MESH.bin [--single]\n");
        MPI_Finalize();
        return 2;
    }
    clvr_error err;
    double rss0 = peak_rss_mib(), c0 = cpu_s(), t0 = clvr_clock_monotonic_s();
    char line[512];
    int rc = 0;
    if (single) {
        clvr_mesh m;
        clvr_status s = clvr_mesh_load(argv[1], NULL, &m, &err);
        double t = clvr_clock_monotonic_s() - t0, c = cpu_s() - c0;
        if (s != CLVR_OK) {
            fprintf(stderr, "%s\n", err.msg);
            rc = 3;
        } else {
            uint64_t e = clvr_mesh_num_elements(&m);
            snprintf(line, sizeof line, "single  %4d %14llu %14llu %8.2f %8.2f %9.0f %9.0f %9.0f %12llu %12llu %6.2f%%", 0,
                     (unsigned long long)(256 + clvr_mesh_vertex_bytes(&m) + clvr_mesh_index_bytes(&m)),
                     (unsigned long long)(256 + clvr_mesh_vertex_bytes(&m) + clvr_mesh_index_bytes(&m)), t, c,
                     peak_rss_mib(), rss0, (double)(clvr_mesh_vertex_bytes(&m) + clvr_mesh_index_bytes(&m)) / 1048576.0,
                     (unsigned long long)e, 0ull, 0.0);
            printf("%s\n", line);
        }
        clvr_mesh_free(&m);
    } else {
        clvr_mpi_share sh;
        clvr_mpi_load_stats st;
        clvr_status s = clvr_mpi_load_share_bin_ex(MPI_COMM_WORLD, argv[1], NULL, 0, &sh, &st, &err);
        double t = clvr_clock_monotonic_s() - t0, c = cpu_s() - c0;
        if (s != CLVR_OK) {
            if (rank == 0) fprintf(stderr, "%s\n", err.msg);
            rc = 3;
        } else {
            snprintf(line, sizeof line, "mpi/%-3d %4d %14llu %14llu %8.2f %8.2f %9.0f %9.0f %9.0f %12llu %12llu %6.2f%%",
                     size, rank, (unsigned long long)st.slice_bytes, (unsigned long long)st.bytes_read, t, c,
                     peak_rss_mib(), rss0,
                     (double)(clvr_mesh_vertex_bytes(&sh.mesh) + clvr_mesh_index_bytes(&sh.mesh)) / 1048576.0,
                     (unsigned long long)sh.owned_elements, (unsigned long long)st.ghost_elements,
                     100.0 * (double)st.ghost_elements / (double)(sh.owned_elements ? sh.owned_elements : 1));
            /* Rank order, one line each. */
            for (int r = 0; r < size; ++r) {
                if (r == rank) {
                    printf("%s\n", line);
                    fflush(stdout);
                }
                MPI_Barrier(MPI_COMM_WORLD);
            }
        }
        clvr_mpi_share_free(&sh);
    }
    MPI_Finalize();
    return rc;
}
