#!/bin/sh
# test_mpi_load_exit.sh MPIEXEC TEST_MPI_LOAD: a file with a bad vertex
# index, loaded by 3 ranks, must end the job within the timeout with exit
# code 3 (input data) and one message that names the file and the rank
# whose slice held the index; no rank may be left waiting in a collective.
set -u
mpiexec=$1
prog=$2
dir=$(mktemp -d /tmp/clvr-test-mpi-exit-XXXXXX) || exit 1
trap 'rm -rf "$dir"' EXIT
timeout 120 "$mpiexec" -n 3 --oversubscribe "$prog" --exit-check "$dir" >"$dir/out" 2>&1
rc=$?
cat "$dir/out"
fail=0
if [ "$rc" -eq 124 ]; then echo "FAILED: the job hung (killed after 120 s)"; fail=1; fi
if [ "$rc" -ne 3 ]; then echo "FAILED: exit code $rc, expected 3"; fail=1; fi
n=$(grep -c "^clvr: rank 2 of 3: .*exit-check-bad-index.bin: tets\[.*\] vertex 3 is index" "$dir/out")
if [ "$n" -ne 1 ]; then echo "FAILED: expected one message naming rank 2, the file and the index, got $n"; fail=1; fi
[ "$fail" -eq 0 ] && echo "test_mpi_load_exit: passed"
exit "$fail"
